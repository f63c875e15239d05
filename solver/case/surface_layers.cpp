// Wall particles that follow a 2D shape's surface (issue 31; shape.hpp surface_layers_2d): layer k is
// the level set of the shape's signed distance at (k + 1/2) dp behind the surface, traced by
// marching squares on a grid a quarter of dp fine (exact on straight faces, where the distance is
// linear), then resampled at even arc-length spacing, as near dp as a whole number of points along
// each closed contour allows. So a slanted or curved face has rows of wall particles parallel to it
// at the lattice's spacing, with no steps, and as many particles per layer as the face's length
// holds (the lattice's staircase under a 45-degree face holds 41% too many in its first layer).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "shape.hpp"

namespace spate {

namespace {

// One layer's contours of the level set {distance = level} on the grid, as closed polylines.
class MarchingSquares {
 public:
  MarchingSquares(const std::vector<double>& value, int nx, int ny, double x0, double y0, double step)
      : value_(value), nx_(nx), ny_(ny), x0_(x0), y0_(y0), step_(step) {}

  std::vector<std::vector<std::array<double, 2>>> contours(double level) const {
    // Each cell that the level crosses adds one or two segments between its crossed edges, keyed by
    // edge: a horizontal edge (i, j)-(i + 1, j) is 2 (j nx + i), a vertical one (i, j)-(i, j + 1) that
    // plus one. Every crossed edge of an interior grid ends two segments (the grid's margin keeps the
    // level set off its border), so the segments chain into closed loops.
    std::unordered_map<std::int64_t, std::array<std::int64_t, 2>> next;  // edge -> its two neighbouring edges
    auto link = [&](std::int64_t a, std::int64_t b) {
      auto add = [&](std::int64_t from, std::int64_t to) {
        auto [it, fresh] = next.try_emplace(from, std::array<std::int64_t, 2>{-1, -1});
        (it->second[0] < 0 ? it->second[0] : it->second[1]) = to;
      };
      add(a, b);
      add(b, a);
    };
    for (int j = 0; j + 1 < ny_; ++j)
      for (int i = 0; i + 1 < nx_; ++i) {
        const double v00 = at(i, j) - level, v10 = at(i + 1, j) - level, v11 = at(i + 1, j + 1) - level, v01 = at(i, j + 1) - level;
        const int code = (v00 < 0) | (v10 < 0) << 1 | (v11 < 0) << 2 | (v01 < 0) << 3;
        if (code == 0 || code == 15) continue;
        const std::int64_t bottom = horizontal(i, j), top = horizontal(i, j + 1), left = vertical(i, j), right = vertical(i + 1, j);
        switch (code) {
          case 1: case 14: link(left, bottom); break;
          case 2: case 13: link(bottom, right); break;
          case 3: case 12: link(left, right); break;
          case 4: case 11: link(right, top); break;
          case 6: case 9: link(bottom, top); break;
          case 7: case 8: link(left, top); break;
          case 5: case 10: {  // a saddle: the cell's mean decides which corners connect
            const bool centre_below = (v00 + v10 + v11 + v01) < 0;
            if ((code == 5) == centre_below) link(left, top), link(bottom, right);
            else link(left, bottom), link(right, top);
            break;
          }
          default: break;
        }
      }
    // Walk the loops from their smallest edge (the grid order: the same loops on every run).
    std::vector<std::int64_t> starts;
    starts.reserve(next.size());
    for (const auto& [edge, _] : next) starts.push_back(edge);
    std::sort(starts.begin(), starts.end());
    std::unordered_map<std::int64_t, bool> seen;
    std::vector<std::vector<std::array<double, 2>>> loops;
    for (std::int64_t start : starts) {
      if (seen[start]) continue;
      std::vector<std::array<double, 2>> loop;
      std::int64_t previous = -1, edge = start;
      while (edge >= 0 && !seen[edge]) {
        seen[edge] = true;
        loop.push_back(crossing(edge, level));
        const auto& n = next.at(edge);
        const std::int64_t to = n[0] != previous ? n[0] : n[1];
        previous = edge;
        edge = to;
      }
      if (loop.size() >= 3) loops.push_back(std::move(loop));
    }
    return loops;
  }

 private:
  double at(int i, int j) const { return value_[static_cast<std::size_t>(j) * nx_ + i]; }
  std::int64_t horizontal(int i, int j) const { return 2 * (static_cast<std::int64_t>(j) * nx_ + i); }
  std::int64_t vertical(int i, int j) const { return horizontal(i, j) + 1; }
  // Where the level crosses an edge, by linear interpolation of the distance along it.
  std::array<double, 2> crossing(std::int64_t edge, double level) const {
    const std::int64_t node = edge / 2;
    const int i = static_cast<int>(node % nx_), j = static_cast<int>(node / nx_);
    const int i2 = edge % 2 ? i : i + 1, j2 = edge % 2 ? j + 1 : j;
    const double a = at(i, j) - level, b = at(i2, j2) - level;
    const double f = a / (a - b);
    return {x0_ + (i + f * (i2 - i)) * step_, y0_ + (j + f * (j2 - j)) * step_};
  }

  const std::vector<double>& value_;
  int nx_, ny_;
  double x0_, y0_, step_;
};

// Points at even arc-length spacing around a closed polyline, as near `spacing` as a whole number
// allows, the first half a spacing from the polyline's first vertex.
void resample(const std::vector<std::array<double, 2>>& loop, double spacing, std::vector<std::array<double, 3>>& out) {
  std::vector<double> along(loop.size() + 1, 0.0);
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const auto& a = loop[k];
    const auto& b = loop[(k + 1) % loop.size()];
    along[k + 1] = along[k] + std::hypot(b[0] - a[0], b[1] - a[1]);
  }
  const double length = along.back();
  const long n = std::max(1L, std::lround(length / spacing));
  std::size_t k = 0;
  for (long m = 0; m < n; ++m) {
    const double s = (m + 0.5) * length / n;
    while (k + 1 < loop.size() && along[k + 1] < s) ++k;
    const auto& a = loop[k];
    const auto& b = loop[(k + 1) % loop.size()];
    const double piece = along[k + 1] - along[k];
    const double f = piece > 0 ? (s - along[k]) / piece : 0.0;
    out.push_back({a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), 0.0});
  }
}

}  // namespace

std::vector<std::array<double, 3>> surface_layers_2d(const Shape& shape, double dp, int layers, bool outside) {
  const double step = 0.25 * dp, margin = (layers + 2) * dp;
  const double x0 = shape.lo[0] - margin, y0 = shape.lo[1] - margin;
  const int nx = static_cast<int>(std::ceil((shape.hi[0] - shape.lo[0] + 2 * margin) / step)) + 1;
  const int ny = static_cast<int>(std::ceil((shape.hi[1] - shape.lo[1] + 2 * margin) / step)) + 1;
  std::vector<double> distance(static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x[3] = {x0 + i * step, y0 + j * step, 0.0};
      double normal[3];
      distance[static_cast<std::size_t>(j) * nx + i] = shape.distance(x, normal);
    }
  const MarchingSquares grid(distance, nx, ny, x0, y0, step);
  std::vector<std::array<double, 3>> points;
  for (int k = 0; k < layers; ++k) {
    const double level = (outside ? 1.0 : -1.0) * (k + 0.5) * dp;
    for (const auto& loop : grid.contours(level)) resample(loop, dp, points);
  }
  return points;
}

}  // namespace spate
