// The host plan of the device-resident topology (domain/slab_plan.hpp): pure functions of small
// metadata, shared by HostSlabArrays and the CUDA backend.
#include <gtest/gtest.h>

#include <vector>

#include "domain/slab_plan.hpp"
#include "grid/cell_grid.hpp"

namespace spate {
namespace {

Lattice lattice(int dim, int nx, int ny, int nz, bool periodic_x = false, bool periodic_y = false) {
  Lattice L;
  L.dim = dim;
  L.cells[0] = nx;
  L.cells[1] = ny;
  L.cells[2] = dim == 3 ? nz : 1;
  L.periodic[0] = periodic_x;
  L.periodic[1] = periodic_y;
  for (int a = 0; a < 3; ++a) {
    L.period[a] = L.periodic[a] ? static_cast<float>(L.cells[a]) : 0.0f;
  }
  return L;
}

}  // namespace

TEST(SlabPlan, MigrationHopsPointTowardsTheOwner) {
  // Four slabs over 8 columns: faces 0 2 4 6 8; slab 1 owns columns 2 and 3.
  const std::vector<int> faces{0, 2, 4, 6, 8};
  EXPECT_EQ(migration_hops(faces, 1, false), (std::vector<std::int8_t>{-1, -1, 0, 0, 1, 1, 1, 1}));
  // Periodic: the shorter way round; slab 0 reaches slab 3 by one hop to the left, and the tie
  // (slab 2, two hops either way) goes left, as migrate() always did.
  EXPECT_EQ(migration_hops(faces, 0, true), (std::vector<std::int8_t>{0, 0, 1, 1, -1, -1, -1, -1}));
  // One slab owns everything.
  EXPECT_EQ(migration_hops({0, 5}, 0, true), std::vector<std::int8_t>(5, 0));
}

TEST(SlabPlan, KeysAreCellsOrEmigrantBinsPastThem) {
  Lattice L = lattice(2, 8, 4, 1);
  CellGrid g;
  g.configure(L, 2, 4);  // owns columns 2, 3
  const KeyBins bins{g.cell_count()};
  const std::vector<std::int8_t> hops = migration_hops({0, 2, 4, 8}, 1, false);
  EXPECT_EQ(particle_key(g.view(), L, hops.data(), 2.5f, 0.5f, 0.0f), g.local_cell(2, 0, 0));
  EXPECT_EQ(particle_key(g.view(), L, hops.data(), 3.5f, 3.5f, 0.0f), g.local_cell(3, 3, 0));
  EXPECT_EQ(particle_key(g.view(), L, hops.data(), 1.5f, 0.5f, 0.0f), bins.emigrant_left());
  EXPECT_EQ(particle_key(g.view(), L, hops.data(), 6.5f, 0.5f, 0.0f), bins.emigrant_right());
  // Without hops (ghosts): the halo column is a ghost cell, farther out is lost.
  EXPECT_EQ(particle_key(g.view(), L, nullptr, 1.5f, 0.5f, 0.0f), g.local_cell(1, 0, 0));
  EXPECT_LT(g.local_cell(1, 0, 0), g.cell_count());
  EXPECT_EQ(particle_key(g.view(), L, nullptr, 0.5f, 0.5f, 0.0f), bins.lost());
  // Owned cells, then ghost cells, then the bins: sorting by key puts emigrants last.
  EXPECT_LT(g.local_cell(3, 3, 0), g.owned_cell_count());
  EXPECT_LT(bins.emigrant_left(), bins.emigrant_right());
  EXPECT_LT(bins.emigrant_right(), bins.lost());
  EXPECT_EQ(bins.count(), g.cell_count() + 3);
}

TEST(SlabPlan, HaloSendsTheFirstAndLastColumnsWrappingAcrossPeriodicX) {
  Lattice L = lattice(2, 6, 3, 1, true);
  CellGrid g;
  g.configure(L, 0, 3);
  const std::vector<std::uint32_t> starts{0, 5, 9, 14};  // columns 0, 1, 2 hold 5, 4, 5 particles
  EXPECT_EQ(column_starts_read(g).stride, 3u);
  EXPECT_EQ(column_starts_read(g).count, 4u);
  const HaloSends h = plan_halo_sends(g, starts, true, true);
  EXPECT_EQ(h.range[kLeft], (ParticleRange{0, 5}));
  EXPECT_EQ(h.range[kRight], (ParticleRange{9, 5}));
  EXPECT_EQ(h.shift[kLeft].axis, 0);  // column 0 goes to the last slab, one period up
  EXPECT_EQ(h.shift[kLeft].offset, 6.0f);
  EXPECT_EQ(h.shift[kRight].axis, -1);  // an inner face: no shift
  // No neighbour on a side: nothing sent there.
  const HaloSends edge = plan_halo_sends(g, starts, false, true);
  EXPECT_EQ(edge.range[kLeft].count, 0u);
  EXPECT_THROW(plan_halo_sends(g, std::vector<std::uint32_t>{0, 5}, true, true), std::logic_error);
}

TEST(SlabPlan, InteriorOnlyWithThreeColumns) {
  Lattice L = lattice(3, 10, 4, 4);
  CellGrid g;
  g.configure(L, 2, 6);
  const std::vector<std::uint32_t> starts{0, 10, 25, 40, 50};
  OwnedSplit s = plan_owned_split(g, starts, true, true);
  EXPECT_EQ(s.before, (ParticleRange{0, 10}));
  EXPECT_EQ(s.interior, (ParticleRange{10, 30}));
  EXPECT_EQ(s.after, (ParticleRange{40, 10}));
  // A side without a neighbour has no halo: its edge column is interior.
  s = plan_owned_split(g, starts, false, true);
  EXPECT_EQ(s.before.count, 0u);
  EXPECT_EQ(s.interior, (ParticleRange{0, 40}));
  EXPECT_EQ(s.after, (ParticleRange{40, 10}));
  s = plan_owned_split(g, starts, false, false);
  EXPECT_EQ(s.interior, (ParticleRange{0, 50}));
  EXPECT_EQ(s.before.count + s.after.count, 0u);
  // Two columns between two neighbours: every particle is next to a face.
  g.configure(L, 2, 4);
  s = plan_owned_split(g, std::vector<std::uint32_t>{0, 10, 25}, true, true);
  EXPECT_EQ(s.before, (ParticleRange{0, 25}));
  EXPECT_EQ(s.interior.count + s.after.count, 0u);
  // Periodic y: the same split (images of owned columns are refreshed before the interior pass).
  L = lattice(3, 10, 4, 4, false, true);
  g.configure(L, 2, 6);
  s = plan_owned_split(g, starts, true, true);
  EXPECT_EQ(s.interior, (ParticleRange{10, 30}));
}

}  // namespace spate
