#pragma once
// The topology of one step for a slab whose particles stay in their own arrays (SlabArrays: the
// GPU's device memory): migration to the owning slab, the (cell, id) sort, the halo and its
// refreshes. Only small metadata comes back to the host (emigrant counts, column starts); the
// plan (slab_plan.hpp) decides, the arrays move. The same code runs on HostSlabArrays, the CPU
// backend's particles.
#include <cstdint>
#include <vector>

#include "../comm/transport.hpp"
#include "../grid/cell_grid.hpp"
#include "slab_arrays.hpp"
#include "slab_layout.hpp"
#include "slab_plan.hpp"

namespace spate {

class SlabTopology {
 public:
  // Migrates owned particles to their slabs (several hops after faces moved), sorts them by
  // (cell, id), builds the halo and its periodic images, sorts the ghosts. Returns the particles
  // that moved, summed over all slabs (collective).
  std::int64_t rebuild(SlabArrays& a, const CellGrid& grid, const SlabLayout& layout, SlabTransport& t);

  // The refresh of the ghosts' Refresh fields in two halves: the owners' values are staged first,
  // so work that needs no ghost (interior()) can run before finish_refresh waits for the halo.
  void begin_refresh(SlabArrays& a);
  void finish_refresh(SlabArrays& a, SlabTransport& t);

  const OwnedSplit& split() const { return split_; }
  const HaloSends& sends() const { return sends_; }
  std::size_t ghosts() const { return ghosts_; }
  // Seconds spent so far in the key computations, sorts and cell tables (the per-particle work of a
  // rebuild, without the waits for the neighbours; host time around a device's launches).
  double sort_seconds() const { return sort_seconds_; }

 private:
  std::int64_t migrate(SlabArrays& a, const CellGrid& grid, const SlabLayout& layout, SlabTransport& t);
  void build_halo(SlabArrays& a, const CellGrid& grid, SlabTransport& t);

  std::vector<int> hop_faces_;
  int hop_slab_ = -1;
  HaloSends sends_;
  OwnedSplit split_;
  std::size_t ghosts_ = 0;
  double sort_seconds_ = 0.0;
};

}  // namespace spate
