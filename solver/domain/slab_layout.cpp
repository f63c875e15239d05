#include "slab_layout.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace spate {

SlabLayout SlabLayout::uniform(int columns, int slabs) {
  SlabLayout l;
  l.faces.resize(slabs + 1);
  for (int s = 0; s <= slabs; ++s) l.faces[s] = static_cast<int>(static_cast<std::int64_t>(columns) * s / slabs);
  return l;
}

int SlabLayout::owner_of(int column) const {
  auto it = std::upper_bound(faces.begin() + 1, faces.end() - 1, column);
  return static_cast<int>(it - faces.begin()) - 1;
}

int SlabLayout::narrowest() const {
  int w = faces.back() - faces.front();
  for (int s = 0; s < slabs(); ++s) w = std::min(w, faces[s + 1] - faces[s]);
  return w;
}

SlabLayout balanced_layout(const std::vector<std::int64_t>& weight, int slabs, int min_columns) {
  const int columns = static_cast<int>(weight.size());
  if (columns < slabs * min_columns) throw std::invalid_argument("too few columns for the slabs");
  std::vector<std::int64_t> prefix(columns + 1, 0);
  for (int c = 0; c < columns; ++c) prefix[c + 1] = prefix[c] + weight[c];
  const double total = static_cast<double>(prefix[columns]);
  SlabLayout l;
  l.faces.assign(slabs + 1, 0);
  l.faces[slabs] = columns;
  for (int s = 1; s < slabs; ++s) {
    const double target = total * s / slabs;
    // The first face position whose prefix reaches the target, then the nearer of it and its left.
    int f = static_cast<int>(std::lower_bound(prefix.begin(), prefix.end(), static_cast<std::int64_t>(target)) - prefix.begin());
    if (f > 0 && target - prefix[f - 1] < prefix[std::min(f, columns)] - target) --f;
    const int lo = l.faces[s - 1] + min_columns;
    const int hi = columns - (slabs - s) * min_columns;
    l.faces[s] = std::clamp(f, lo, hi);
  }
  return l;
}

double imbalance(const std::vector<std::int64_t>& per_slab) {
  if (per_slab.empty()) return 1.0;
  const double total = static_cast<double>(std::accumulate(per_slab.begin(), per_slab.end(), std::int64_t{0}));
  if (total <= 0) return 1.0;
  const double mean = total / static_cast<double>(per_slab.size());
  return static_cast<double>(*std::max_element(per_slab.begin(), per_slab.end())) / mean;
}

}  // namespace spate
