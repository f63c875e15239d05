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

}  // namespace spate
