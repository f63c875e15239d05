// Particle pack/unpack (solver/particles/particle_pack.hpp): what halos, migration and checkpoint
// gathers send must arrive bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "particles/particle_pack.hpp"

namespace spate {
namespace {

// Every field of particle i gets a distinct value derived from i and the field's position.
ParticleStore numbered_store(int dim, std::size_t n) {
  ParticleStore p(dim);
  p.resize(n);
  auto fields = p.fields();
  for (std::size_t f = 0; f < fields.size(); ++f) {
    for (std::size_t i = 0; i < n; ++i) {
      char* at = fields[f].bytes() + i * fields[f].elem_size;
      if (fields[f].elem_size == 1) {
        *at = static_cast<char>((i * 7 + f) % 251);
      } else if (fields[f].name == "id") {
        const std::uint32_t v = static_cast<std::uint32_t>(1000 + i);
        std::memcpy(at, &v, sizeof v);
      } else {
        const float v = 0.25f * static_cast<float>(i) + 100.0f * static_cast<float>(f) + 0.1f;
        std::memcpy(at, &v, sizeof v);
      }
    }
  }
  p.set_owned(n);
  return p;
}

bool same_particle(ParticleStore& a, std::size_t i, ParticleStore& b, std::size_t j, FieldSet set) {
  auto fa = a.fields(), fb = b.fields();
  for (std::size_t f = 0; f < fa.size(); ++f) {
    if (!in_set(fa[f], set)) continue;
    const std::size_t s = fa[f].elem_size;
    if (std::memcmp(fa[f].bytes() + i * s, fb[f].bytes() + j * s, s) != 0) return false;
  }
  return true;
}

TEST(ParticlePack, AllFieldsRoundTrip) {
  for (int dim : {2, 3}) {
    ParticleStore src = numbered_store(dim, 50);
    const std::vector<std::uint32_t> picked = {3, 0, 49, 17, 17};
    const Bytes buffer = pack_particles(src, picked, FieldSet::All);
    EXPECT_EQ(packed_count(buffer), picked.size());
    ParticleStore dst(dim);
    EXPECT_EQ(unpack_append(dst, buffer, FieldSet::All), picked.size());
    ASSERT_EQ(dst.size(), picked.size());
    for (std::size_t k = 0; k < picked.size(); ++k)
      EXPECT_TRUE(same_particle(src, picked[k], dst, k, FieldSet::All)) << dim << "D, slot " << k;
  }
}

TEST(ParticlePack, GhostSetCarriesWhatNeighboursNeed) {
  ParticleStore src = numbered_store(3, 10);
  ParticleStore dst = numbered_store(3, 4);  // existing particles stay untouched
  ParticleStore before = numbered_store(3, 4);
  const std::vector<std::uint32_t> picked = {1, 8};
  unpack_append(dst, pack_particles(src, picked, FieldSet::Ghost), FieldSet::Ghost);
  ASSERT_EQ(dst.size(), 6u);
  EXPECT_EQ(dst.owned(), 4u);  // appended particles are ghosts
  for (std::size_t k = 0; k < 4; ++k) EXPECT_TRUE(same_particle(before, k, dst, k, FieldSet::All));
  for (std::size_t k = 0; k < picked.size(); ++k) EXPECT_TRUE(same_particle(src, picked[k], dst, 4 + k, FieldSet::Ghost));
  // Positions, velocities, density, pressure, id and material are ghost fields; rates are not.
  for (auto& f : src.fields()) {
    const bool expected = f.name == "x" || f.name == "y" || f.name == "z" || f.name == "vx" || f.name == "vy" ||
                          f.name == "vz" || f.name == "density" || f.name == "pressure" || f.name == "id" || f.name == "material";
    EXPECT_EQ(in_set(f, FieldSet::Ghost), expected) << f.name;
  }
}

TEST(ParticlePack, ShiftMovesOnlyTheChosenAxis) {
  ParticleStore src = numbered_store(3, 5);
  const std::vector<std::uint32_t> picked = {2};
  ParticleStore dst(3);
  // A lattice periodic along y whose first cell layer holds the picked particle: its copy lands one
  // period up, in the ghost layer.
  Lattice L;
  L.origin[1] = src.pos[1][2] - 0.25f;
  L.cell_size[1] = 0.5f;
  L.inv_cell[1] = 2.0f;
  L.cells[1] = 5;
  L.periodic[1] = true;
  L.period[1] = 2.5f;
  unpack_append(dst, pack_particles(src, picked, FieldSet::Ghost, periodic_shift(L, 1, true)), FieldSet::Ghost);
  EXPECT_EQ(dst.pos[0][0], src.pos[0][2]);
  EXPECT_EQ(dst.pos[1][0], src.pos[1][2] + 2.5f);
  EXPECT_EQ(dst.pos[2][0], src.pos[2][2]);
  EXPECT_EQ(dst.vel[1][0], src.vel[1][2]);
}

TEST(ParticlePack, RefreshOverwritesOnlyChangingFields) {
  ParticleStore src = numbered_store(2, 6);
  ParticleStore dst = numbered_store(2, 6);
  for (std::size_t i = 0; i < 6; ++i) {
    src.pressure[i] = -1.0f * static_cast<float>(i);
    src.density[i] = 999.0f;
    src.pos[0][i] = 123.0f;  // not a refresh field: must not arrive
  }
  const std::vector<std::uint32_t> picked = {0, 5};
  const std::vector<std::uint32_t> slots = {3, 1};
  unpack_into(dst, pack_particles(src, picked, FieldSet::Refresh), FieldSet::Refresh, slots);
  EXPECT_EQ(dst.pressure[3], src.pressure[0]);
  EXPECT_EQ(dst.pressure[1], src.pressure[5]);
  EXPECT_EQ(dst.density[1], 999.0f);
  EXPECT_NE(dst.pos[0][1], 123.0f);
  EXPECT_NE(dst.density[0], 999.0f);  // slots not listed stay as they were
  EXPECT_THROW(unpack_into(dst, pack_particles(src, picked, FieldSet::Refresh), FieldSet::Refresh,
                           std::vector<std::uint32_t>{1}),
               std::runtime_error);
}

TEST(ParticlePack, EmptyAndTruncatedBuffers) {
  ParticleStore dst(3);
  EXPECT_EQ(unpack_append(dst, Bytes{}, FieldSet::All), 0u);
  ParticleStore src = numbered_store(3, 4);
  const std::vector<std::uint32_t> none;
  EXPECT_EQ(packed_count(pack_particles(src, none, FieldSet::All)), 0u);
  const std::vector<std::uint32_t> picked = {0, 1};
  Bytes cut = pack_particles(src, picked, FieldSet::All);
  cut.resize(cut.size() - 3);
  EXPECT_THROW(unpack_append(dst, cut, FieldSet::All), std::runtime_error);
}

TEST(ParticleStore, PermuteAndRemoveKeepParticlesWhole) {
  ParticleStore p = numbered_store(3, 6);
  ParticleStore original = numbered_store(3, 6);
  const std::vector<std::uint32_t> perm = {2, 0, 1};
  p.permute(3, perm);  // slots 3..5 now hold old 5, 3, 4
  EXPECT_TRUE(same_particle(p, 3, original, 5, FieldSet::All));
  EXPECT_TRUE(same_particle(p, 4, original, 3, FieldSet::All));
  EXPECT_TRUE(same_particle(p, 0, original, 0, FieldSet::All));
  p.remove_owned_if({1, 0, 0, 1, 0, 0});
  ASSERT_EQ(p.size(), 4u);
  EXPECT_EQ(p.owned(), 4u);
  EXPECT_TRUE(same_particle(p, 0, original, 1, FieldSet::All));
  EXPECT_TRUE(same_particle(p, 2, original, 3, FieldSet::All));
}

// x + period rounds to nearest: for a particle within an ulp of a cell face the sum can land on the
// next face, one cell beyond the ghost layer, where a slab's grid has no cell (the resident path
// stopped with "ghost outside the local grid"). periodic_copy keeps every copy in its layer, moved
// by no more than a few ulps. The lattices are searched for such particles, so the test holds one.
TEST(PeriodicCopy, ACopyRoundedOntoTheNextFaceStaysInItsGhostLayer) {
  int rounded_out[2] = {0, 0};
  for (int trial = 0; trial < 200; ++trial) {
    Lattice L;
    L.dim = 2;
    L.origin[0] = -0.0137f * static_cast<float>(trial % 17);
    L.cell_size[0] = 0.026f + 0.00071f * static_cast<float>(trial);
    L.inv_cell[0] = 1.0f / L.cell_size[0];
    L.cells[0] = 7 + trial % 53;
    L.periodic[0] = true;
    L.period[0] = static_cast<float>(L.cells[0]) * L.cell_size[0];
    for (const bool up : {true, false}) {
      const Shift shift = periodic_shift(L, 0, up);
      const int source_cell = up ? 0 : L.cells[0] - 1, target = up ? L.cells[0] : -1;
      // Walk a few ulps around both faces of the source cell.
      for (const float face : {L.origin[0] + static_cast<float>(source_cell) * L.cell_size[0],
                               L.origin[0] + static_cast<float>(source_cell + 1) * L.cell_size[0]}) {
        float x = face;
        for (int k = 0; k < 8; ++k) x = nextafterf(x, -INFINITY);
        for (int k = 0; k < 16; ++k, x = nextafterf(x, INFINITY)) {
          if (L.cell_of(x, 0) != source_cell) continue;
          const float plain = x + shift.offset;
          if (L.cell_of(plain, 0) != target) ++rounded_out[up ? 0 : 1];
          const float copy = shift.apply(x);
          EXPECT_EQ(L.cell_of(copy, 0), target) << "x = " << x << ", trial " << trial;
          // No further than the sum's own rounding error (half an ulp of the larger term) and the few
          // ulps the lattice's float arithmetic puts between a face and its cell.
          const float big = std::max(std::fabs(x), std::fabs(shift.offset));
          EXPECT_LE(std::fabs(copy - plain), 4.0f * (nextafterf(big, INFINITY) - big)) << "x = " << x;
        }
      }
    }
  }
  // The searched lattices do contain copies that plain addition puts outside the layer.
  EXPECT_GT(rounded_out[0] + rounded_out[1], 0);
}

}  // namespace
}  // namespace spate
