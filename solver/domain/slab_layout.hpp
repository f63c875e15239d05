#pragma once
// Which slab owns which x columns of the global cell lattice. Faces are column indices:
// slab s owns [faces[s], faces[s+1]).
#include <cstdint>
#include <vector>

namespace spate {

struct SlabLayout {
  std::vector<int> faces;

  static SlabLayout uniform(int columns, int slabs);
  int slabs() const { return static_cast<int>(faces.size()) - 1; }
  int owner_of(int column) const;
  int narrowest() const;
  bool operator==(const SlabLayout&) const = default;
};

// Faces that split the per-column work `weight` into `slabs` nearly equal parts, each slab at
// least `min_columns` wide. Deterministic: depends only on the histogram.
SlabLayout balanced_layout(const std::vector<std::int64_t>& weight, int slabs, int min_columns);

// max/mean of per-slab totals (1 is perfect balance).
double imbalance(const std::vector<std::int64_t>& per_slab);

// Work per x column in the two neighbour phases of a step. They are timed apart because they scale
// with different particles (walls, fluid), but the slabs no longer wait for each other between
// them: the halo refresh that separates them is waited for after the interior fluid pass, so a
// step lasts about max_s (wall_s + fluid_s).
struct PhaseCosts {
  std::vector<std::int64_t> wall;   // equation of state and wall state, per column
  std::vector<std::int64_t> fluid;  // fluid rates (and summation density), per column
};
// Per-slab totals of one phase histogram under `layout`.
std::vector<std::int64_t> slab_totals(const SlabLayout& layout, const std::vector<std::int64_t>& per_column);
// max_s (wall_s + fluid_s): the length of a step (in the histogram's units) under `layout`.
std::int64_t critical_path(const SlabLayout& layout, const PhaseCosts& costs);
// critical_path / mean over slabs of (wall_s + fluid_s): 1 when the work is perfectly even.
double phase_imbalance(const SlabLayout& layout, const PhaseCosts& costs);
// Faces that shorten the critical path: the balanced layout of the summed histogram, then single
// faces moved a column at a time while the critical path shrinks (the rounding to whole columns).
// Deterministic: depends only on the histograms, so every slab that holds the same (summed)
// histograms picks the same faces.
SlabLayout balanced_layout(const PhaseCosts& costs, int slabs, int min_columns);

}  // namespace spate
