#include "slab_topology.hpp"

#include <chrono>
#include <stdexcept>

namespace spate {

namespace {
// Runs body() and adds its seconds to `total`.
template <class Body>
void timed(double& total, Body&& body) {
  const auto t = std::chrono::steady_clock::now();
  body();
  total += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

std::int64_t SlabTopology::rebuild(SlabArrays& a, const CellGrid& grid, const SlabLayout& layout, SlabTransport& t) {
  const std::int64_t moved = migrate(a, grid, layout, t);
  build_halo(a, grid, t);
  return moved;
}

// One sort does both jobs: leavers get keys past every cell, so after sorting by (key, id) the
// particles that stay are sorted by (cell, id) and the leavers of each side are one range at the
// end. When nobody anywhere moves (the collective sum), the sort is final; otherwise the
// immigrants are appended and the loop sorts again (and hops on, after faces moved).
std::int64_t SlabTopology::migrate(SlabArrays& a, const CellGrid& grid, const SlabLayout& layout, SlabTransport& t) {
  if (layout.faces != hop_faces_ || t.slab() != hop_slab_) {
    a.set_migration_hops(migration_hops(layout.faces, t.slab(), t.periodic_x));
    hop_faces_ = layout.faces;
    hop_slab_ = t.slab();
  }
  a.truncate(a.owned());  // ghosts are stale once owned particles moved
  const KeyBins bins{grid.cell_count()};
  std::int64_t total = 0;
  for (;;) {
    timed(sort_seconds_, [&] {
      a.compute_keys(grid, 0, a.owned(), true);
      a.sort_by_key(0, a.owned());
      a.build_table(grid);
    });
    // Starts of the left-emigrant, right-emigrant and lost bins, and the end.
    const auto e = a.table_entries(TableRead{bins.emigrant_left(), 1, 4});
    // The simulation stops runs with particles outside the domain before this; reaching it is a
    // bug in ownership, not bad input.
    if (e[2] != e[3]) throw std::logic_error("SlabTopology: owned particle outside the local grid");
    const ParticleRange left{e[0], e[1] - e[0]}, right{e[1], e[2] - e[1]};
    const std::int64_t moved = t.sum(static_cast<std::int64_t>(left.count + right.count));
    if (moved == 0) break;
    total += moved;
    a.stage(kLeft, FieldSet::All, left, {});
    a.stage(kRight, FieldSet::All, right, {});
    a.exchange(t, FieldSet::All);
    a.truncate(left.first);
    a.append_received(kLeft, FieldSet::All);
    a.append_received(kRight, FieldSet::All);
    a.set_owned(a.size());
  }
  return total;
}

void SlabTopology::build_halo(SlabArrays& a, const CellGrid& grid, SlabTransport& t) {
  const int s = t.slab();
  const auto starts = a.table_entries(column_starts_read(grid));
  const bool has_left = t.left_of(s) >= 0, has_right = t.right_of(s) >= 0;
  sends_ = plan_halo_sends(grid, starts, has_left, has_right);
  split_ = plan_owned_split(grid, starts, has_left, has_right);
  a.stage(kLeft, FieldSet::Ghost, sends_.range[kLeft], sends_.shift[kLeft]);
  a.stage(kRight, FieldSet::Ghost, sends_.range[kRight], sends_.shift[kRight]);
  const auto received = a.exchange(t, FieldSet::Ghost);
  a.append_received(kLeft, FieldSet::Ghost);
  a.append_received(kRight, FieldSet::Ghost);
  a.forget_images();
  const Lattice& L = grid.lattice();
  for (int axis = 1; axis < L.dim; ++axis)
    if (L.periodic[axis]) a.make_images(grid, axis);
  const std::size_t owned = a.owned();
  timed(sort_seconds_, [&] {
    a.compute_keys(grid, owned, a.size(), false);
    a.sort_by_key(owned, a.size());
    a.build_table(grid);
  });
  const KeyBins bins{grid.cell_count()};
  const auto lost = a.table_entries(TableRead{bins.lost(), 1, 2});
  if (lost[0] != lost[1]) throw std::logic_error("SlabTopology: ghost outside the local grid");
  a.record_halo_slots(received[kLeft], received[kRight]);
  ghosts_ = a.size() - owned;
}

void SlabTopology::begin_refresh(SlabArrays& a) {
  a.stage(kLeft, FieldSet::Refresh, sends_.range[kLeft], {});
  a.stage(kRight, FieldSet::Refresh, sends_.range[kRight], {});
  // Images of owned columns need no halo: ready for the interior pass.
  a.refresh_images(ImagePart::Local);
}

void SlabTopology::finish_refresh(SlabArrays& a, SlabTransport& t) {
  a.exchange(t, FieldSet::Refresh);
  a.scatter_received(kLeft);
  a.scatter_received(kRight);
  // Images of halo columns after the halo: they copy the ghosts' fresh values.
  a.refresh_images(ImagePart::Halo);
}

}  // namespace spate
