// Wall particles that follow a 3D shape's surface (issue 31; shape.hpp surface_layers): layer k on
// the level set of the shape's signed distance at (k + 1/2) dp behind the surface, dp^-2 particles
// per square metre of it, spread evenly. A surface in 3D has no arc length to space points along
// (the 2D layers' way, surface_layers.cpp), so each layer is sampled in three steps:
//  1. candidates: the points of a grid dp/2 fine whose distance lies within dp/4 of the level,
//     moved onto it along the distance's gradient (a Newton step on the signed distance), about
//     (2/dp)^2 of them per square metre of the level set; the same grid measures the level set's
//     area, and the layer keeps area / dp^2 of them, the lattice walls' number under a face;
//  2. weighted sample elimination (Yuksel 2015, "Sample elimination for generating Poisson disk
//     sample sets"): the most crowded candidate goes first until that many are left, a blue-noise
//     set with no two points close;
//  3. a few steps of short-range repulsion along the level set, which evens the set towards the
//     hexagonal packing (neighbours 1.07 dp apart).
// Every step visits points in a fixed order: the same particles on every run, rank and split.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <queue>
#include <unordered_map>

#include "point3.hpp"
#include "shape.hpp"

namespace spate {

namespace {

using P3 = std::array<double, 3>;

constexpr double kCandidateStep = 0.5;  // [dp]: the candidates' grid (1/kCandidateStep^2 per dp^2 of surface)
constexpr int kRelaxSteps = 20;
constexpr int kProjectEvery = 4;

// Points hashed into cubic cells, for the neighbours within one cell's width.
class PointCells {
 public:
  PointCells(const std::vector<P3>& points, double cell) : points_(points), inv_(1.0 / cell) {
    order_.resize(points.size());
    std::vector<std::int64_t> keys(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) keys[i] = key(points[i]), order_[i] = static_cast<std::uint32_t>(i);
    std::stable_sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
    for (std::size_t m = 0; m < order_.size();) {
      std::size_t e = m;
      while (e < order_.size() && keys[order_[e]] == keys[order_[m]]) ++e;
      range_[keys[order_[m]]] = {m, e};
      m = e;
    }
  }
  // Calls f(j) for every point j in the 27 cells around x, cell by cell in a fixed order.
  template <class F>
  void near(const P3& x, F&& f) const {
    const std::int64_t c[3] = {cell(x[0]), cell(x[1]), cell(x[2])};
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = range_.find(pack(c[0] + dx, c[1] + dy, c[2] + dz));
          if (it == range_.end()) continue;
          for (std::size_t m = it->second.first; m < it->second.second; ++m) f(order_[m]);
        }
  }

 private:
  std::int64_t cell(double v) const { return static_cast<std::int64_t>(std::floor(v * inv_)); }
  static std::int64_t pack(std::int64_t i, std::int64_t j, std::int64_t k) {
    return ((i & 0x1fffff) << 42) | ((j & 0x1fffff) << 21) | (k & 0x1fffff);
  }
  std::int64_t key(const P3& x) const { return pack(cell(x[0]), cell(x[1]), cell(x[2])); }

  const std::vector<P3>& points_;
  double inv_;
  std::vector<std::uint32_t> order_;
  std::unordered_map<std::int64_t, std::pair<std::size_t, std::size_t>> range_;
};


// Moves x towards the level set {distance = level} along the distance's gradient, `steps` Newton
// steps (each exact where the level set is flat); `normal`: the gradient at the last x queried.
void project(const Shape& shape, double level, P3& x, P3& normal, int steps) {
  for (int it = 0; it < steps; ++it) {
    const double d = shape.distance(x.data(), normal.data()) - level;
    for (int a = 0; a < 3; ++a) x[a] -= d * normal[a];
  }
}

// Keeps `keep` of the candidates, removing the most crowded first (Yuksel 2015, eqs. 1-2, with his
// alpha = 8, beta = 0.65, gamma = 1.5); returns the kept indices in the candidates' order.
std::vector<std::uint32_t> eliminate(const std::vector<P3>& x, std::size_t keep, double area) {
  const std::size_t n = x.size();
  if (keep >= n) {
    std::vector<std::uint32_t> all(n);
    for (std::size_t i = 0; i < n; ++i) all[i] = static_cast<std::uint32_t>(i);
    return all;
  }
  const double r_max = std::sqrt(area / (2.0 * std::sqrt(3.0) * static_cast<double>(keep)));
  const double r_min = r_max * (1.0 - std::pow(static_cast<double>(keep) / static_cast<double>(n), 1.5)) * 0.65;
  const double reach = 2.0 * r_max;
  auto weight = [&](double d) {
    const double w = 1.0 - std::max(d, r_min) / reach;
    const double w2 = w * w, w4 = w2 * w2;
    return w4 * w4;
  };
  const PointCells cells(x, reach);
  std::vector<double> w(n, 0.0);
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < static_cast<std::int64_t>(n); ++i)
    cells.near(x[i], [&](std::uint32_t j) {
      const double d2 = point3::distance2(x[i], x[j]);
      if (j != i && d2 < reach * reach) w[i] += weight(std::sqrt(d2));
    });
  // A max-heap of (weight, index); an entry whose weight is no longer the point's is stale.
  using Entry = std::pair<double, std::uint32_t>;
  std::priority_queue<Entry> heap;
  for (std::size_t i = 0; i < n; ++i) heap.push({w[i], static_cast<std::uint32_t>(i)});
  std::vector<char> gone(n, 0);
  for (std::size_t left = n; left > keep;) {
    const auto [wi, i] = heap.top();
    heap.pop();
    if (gone[i] || wi != w[i]) continue;
    gone[i] = 1;
    --left;
    cells.near(x[i], [&](std::uint32_t j) {
      const double d2 = point3::distance2(x[i], x[j]);
      if (gone[j] || d2 >= reach * reach) return;
      w[j] -= weight(std::sqrt(d2));
      heap.push({w[j], j});
    });
  }
  std::vector<std::uint32_t> kept;
  kept.reserve(keep);
  for (std::size_t i = 0; i < n; ++i)
    if (!gone[i]) kept.push_back(static_cast<std::uint32_t>(i));
  return kept;
}

// Evens the points along their level set: each step moves every point (all at once) away from its
// neighbours within 1.6 spacings, in the level set's tangent plane, by at most a tenth of the
// spacing. A step leaves a point within (0.1 spacing)^2 / (2 R) of a level set of curvature radius
// R: it goes back onto it (a Newton step, a distance query) every kProjectEvery steps and twice at
// the end.
void relax(const Shape& shape, double level, double spacing, std::vector<P3>& x, std::vector<P3>& normal) {
  const double reach = 1.6 * spacing;
  const auto n = static_cast<std::int64_t>(x.size());
  std::vector<P3> push(x.size());
  for (int step = 0; step < kRelaxSteps; ++step) {
    const PointCells cells(x, reach);
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < n; ++i) {
      P3 f{0, 0, 0};
      cells.near(x[i], [&](std::uint32_t j) {
        const double d2 = point3::distance2(x[i], x[j]);
        if (j == i || d2 >= reach * reach || d2 == 0.0) return;
        const double d = std::sqrt(d2), q = 1.0 - d / reach;
        for (int a = 0; a < 3; ++a) f[a] += q * q * (x[i][a] - x[j][a]) / d;
      });
      const double along = f[0] * normal[i][0] + f[1] * normal[i][1] + f[2] * normal[i][2];
      for (int a = 0; a < 3; ++a) f[a] -= along * normal[i][a];
      const double len = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
      const double scale = std::min(0.1 * spacing, 0.5 * spacing * len) / std::max(len, 1e-300);
      for (int a = 0; a < 3; ++a) push[i][a] = scale * f[a];
    }
    const bool last = step + 1 == kRelaxSteps;
    const int newton = last ? 2 : (step + 1) % kProjectEvery == 0 ? 1 : 0;
#pragma omp parallel for schedule(static)
    for (std::int64_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) x[i][a] += push[i][a];
      project(shape, level, x[i], normal[i], newton);
    }
  }
}

}  // namespace

std::vector<std::array<double, 3>> surface_layers_3d(const Shape& shape, double dp, int layers, bool outside) {
  const double step = kCandidateStep * dp, margin = (layers + 1) * dp;
  const double sign = outside ? 1.0 : -1.0;
  // Candidates lie within step/2 of a level, the sites that measure its area within dp of it:
  // distances in [low, high) hold them.
  const double low = outside ? 0.5 * dp - dp : -(layers - 0.5) * dp - dp;
  const double high = outside ? (layers - 0.5) * dp + dp : -0.5 * dp + dp;
  // Each layer's area by the coarea formula: the integral of hat((d - level) / dp) / dp over the
  // volume is the level set's area (exactly where the area varies linearly with the level), summed
  // on the grid, where the hat's smoothness keeps the sum's lattice error small (counting the sites
  // within step/2 of a sphere's level misjudges its area by up to 7%).
  std::vector<double> area(layers, 0.0);
  int n[3];
  for (int a = 0; a < 3; ++a) n[a] = static_cast<int>(std::ceil((shape.hi[a] - shape.lo[a] + 2 * margin) / step)) + 1;
  // One slice of the grid (its x index) at a time, in parallel; joined in slice order below.
  struct Slice {
    std::vector<std::vector<P3>> candidates, normals;
    std::vector<double> area;
  };
  std::vector<Slice> slices(static_cast<std::size_t>(n[0]));
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < n[0]; ++i) {
    Slice& out = slices[static_cast<std::size_t>(i)];
    out.candidates.resize(layers), out.normals.resize(layers), out.area.assign(layers, 0.0);
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2];) {
        P3 x{shape.lo[0] - margin + i * step, shape.lo[1] - margin + j * step, shape.lo[2] - margin + k * step};
        P3 normal;
        const double d = shape.distance(x.data(), normal.data());
        // The distance changes by at most the step between sites: skip the sites that cannot reach
        // the band.
        if (d < low) {
          k += std::max(1, static_cast<int>(std::floor((low - d) / step)));
          continue;
        }
        if (d >= high) {
          k += static_cast<int>(std::floor((d - high) / step)) + 1;
          continue;
        }
        ++k;
        const double depth = sign * d / dp - 0.5;  // the layer's number, where on a level
        for (long m = std::max(0L, static_cast<long>(std::floor(depth))); m <= std::min<long>(layers - 1, static_cast<long>(std::floor(depth)) + 1); ++m)
          out.area[m] += std::max(0.0, 1.0 - std::fabs(depth - static_cast<double>(m))) * step * step * step / dp;
        const long layer = std::lround(depth);
        if (layer < 0 || layer >= layers || std::fabs(depth - static_cast<double>(layer)) * dp >= 0.5 * step) continue;
        // Onto the level (the Newton step from the distance just queried; relax() refines it).
        const double level = sign * (static_cast<double>(layer) + 0.5) * dp;
        for (int a = 0; a < 3; ++a) x[a] -= (d - level) * normal[a];
        out.candidates[layer].push_back(x);
        out.normals[layer].push_back(normal);
      }
  }
  std::vector<std::vector<P3>> candidates(layers), normals(layers);
  for (const Slice& slice : slices)
    for (int layer = 0; layer < layers; ++layer) {
      candidates[layer].insert(candidates[layer].end(), slice.candidates[layer].begin(), slice.candidates[layer].end());
      normals[layer].insert(normals[layer].end(), slice.normals[layer].begin(), slice.normals[layer].end());
      area[layer] += slice.area[layer];
    }
  std::vector<P3> points;
  for (int layer = 0; layer < layers; ++layer) {
    const std::vector<P3>& c = candidates[layer];
    const auto keep = static_cast<std::size_t>(std::llround(area[layer] / (dp * dp)));
    std::vector<P3> x, normal;
    for (std::uint32_t m : eliminate(c, keep, area[layer])) x.push_back(c[m]), normal.push_back(normals[layer][m]);
    relax(shape, sign * (layer + 0.5) * dp, std::sqrt(2.0 / std::sqrt(3.0)) * dp, x, normal);
    points.insert(points.end(), x.begin(), x.end());
  }
  return points;
}

}  // namespace spate
