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

std::vector<std::int64_t> slab_totals(const SlabLayout& layout, const std::vector<std::int64_t>& per_column) {
  std::vector<std::int64_t> out(layout.slabs(), 0);
  for (int s = 0; s < layout.slabs(); ++s)
    for (int c = layout.faces[s]; c < layout.faces[s + 1]; ++c) out[s] += per_column[c];
  return out;
}

std::int64_t critical_path(const SlabLayout& layout, const PhaseCosts& costs) {
  const auto wall = slab_totals(layout, costs.wall), fluid = slab_totals(layout, costs.fluid);
  std::int64_t longest = 0;
  for (std::size_t s = 0; s < wall.size(); ++s) longest = std::max(longest, wall[s] + fluid[s]);
  return longest;
}

double phase_imbalance(const SlabLayout& layout, const PhaseCosts& costs) {
  const std::int64_t total = std::accumulate(costs.wall.begin(), costs.wall.end(), std::int64_t{0}) +
                             std::accumulate(costs.fluid.begin(), costs.fluid.end(), std::int64_t{0});
  if (total <= 0) return 1.0;
  return static_cast<double>(critical_path(layout, costs)) * layout.slabs() / static_cast<double>(total);
}

SlabLayout balanced_layout(const PhaseCosts& costs, int slabs, int min_columns) {
  std::vector<std::int64_t> sum(costs.wall.size());
  for (std::size_t c = 0; c < sum.size(); ++c) sum[c] = costs.wall[c] + costs.fluid[c];
  SlabLayout best = balanced_layout(sum, slabs, min_columns);
  std::int64_t best_path = critical_path(best, costs);
  // Hill climbing over single-column face moves. Each accepted move shortens the path by at least
  // one unit, so it ends; the columns are few (tens to hundreds), so a full sweep is cheap.
  for (bool improved = true; improved;) {
    improved = false;
    for (int f = 1; f < slabs; ++f) {
      for (const int delta : {-1, 1}) {
        SlabLayout trial = best;
        trial.faces[f] += delta;
        if (trial.faces[f] - trial.faces[f - 1] < min_columns || trial.faces[f + 1] - trial.faces[f] < min_columns) continue;
        const std::int64_t path = critical_path(trial, costs);
        if (path < best_path) {
          best = trial;
          best_path = path;
          improved = true;
        }
      }
    }
  }
  return best;
}

}  // namespace spate
