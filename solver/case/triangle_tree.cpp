#include "triangle_tree.hpp"

#include "point3.hpp"

#include <algorithm>
#include <limits>

namespace spate {

namespace {
using P3 = TriangleTree::P3;
using point3::dot, point3::sub;
P3 along(const P3& a, const P3& u, double t) { return {a[0] + t * u[0], a[1] + t * u[1], a[2] + t * u[2]}; }

// The squared distance from x to a box (0 inside).
double box_distance2(const P3& x, const P3& lo, const P3& hi) {
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double out = std::max({lo[a] - x[a], x[a] - hi[a], 0.0});
    d2 += out * out;
  }
  return d2;
}
constexpr std::uint32_t kLeafTriangles = 4;
}  // namespace

P3 closest_on_triangle(const P3& p, const P3& a, const P3& b, const P3& c) {
  // Which of the triangle's seven Voronoi regions (three vertices, three edges, the face) holds p.
  const P3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const P3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return along(a, ab, d1 / (d1 - d3));
  const P3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return along(a, ac, d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double den = 1.0 / (va + vb + vc);
  const double v = vb * den, w = vc * den;
  return {a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w};
}

TriangleTree::TriangleTree(const std::vector<P3>& points, const std::vector<std::array<long long, 3>>& triangles)
    : points_(points), triangles_(triangles) {
  order_.resize(triangles.size());
  centroid_.resize(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    order_[t] = static_cast<std::uint32_t>(t);
    for (int a = 0; a < 3; ++a)
      centroid_[t][a] = (points[triangles[t][0]][a] + points[triangles[t][1]][a] + points[triangles[t][2]][a]) / 3.0;
  }
  nodes_.reserve(2 * triangles.size() / kLeafTriangles + 2);
  nodes_.push_back({});
  if (!triangles.empty()) leaf_or_split(0, 0, static_cast<std::uint32_t>(triangles.size()));
  centroid_.clear();
  centroid_.shrink_to_fit();
}

void TriangleTree::leaf_or_split(std::uint32_t node, std::uint32_t begin, std::uint32_t end) {
  P3 lo{std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  P3 hi{-lo[0], -lo[1], -lo[2]};
  P3 clo = lo, chi = hi;
  for (std::uint32_t m = begin; m < end; ++m) {
    const std::uint32_t t = order_[m];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], points_[triangles_[t][k]][a]), hi[a] = std::max(hi[a], points_[triangles_[t][k]][a]);
    for (int a = 0; a < 3; ++a) clo[a] = std::min(clo[a], centroid_[t][a]), chi[a] = std::max(chi[a], centroid_[t][a]);
  }
  nodes_[node].lo = lo, nodes_[node].hi = hi;
  if (end - begin <= kLeafTriangles) {
    nodes_[node].first = begin, nodes_[node].count = end - begin;
    return;
  }
  // Split at the median centroid along the centroids' longest extent (ties by triangle number).
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (chi[a] - clo[a] > chi[axis] - clo[axis]) axis = a;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](std::uint32_t a, std::uint32_t b) {
    return centroid_[a][axis] < centroid_[b][axis] || (centroid_[a][axis] == centroid_[b][axis] && a < b);
  });
  const auto children = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back({});
  nodes_.push_back({});
  nodes_[node].first = children, nodes_[node].count = 0;
  leaf_or_split(children, begin, mid);
  leaf_or_split(children + 1, mid, end);
}

TriangleTree::Nearest TriangleTree::nearest(const P3& x) const {
  Nearest best;
  best.distance2 = std::numeric_limits<double>::infinity();
  if (triangles_.empty()) return best;
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (box_distance2(x, n.lo, n.hi) > best.distance2) continue;
    if (n.count > 0) {
      for (std::uint32_t m = n.first; m < n.first + n.count; ++m) {
        const std::uint32_t t = order_[m];
        const auto& tri = triangles_[t];
        const P3 c = closest_on_triangle(x, points_[tri[0]], points_[tri[1]], points_[tri[2]]);
        const P3 r = sub(x, c);
        const double d2 = dot(r, r);
        if (d2 < best.distance2 || (d2 == best.distance2 && t < best.triangle)) best = {c, d2, t};
      }
      continue;
    }
    // The nearer child last on the stack: searched first.
    const double d0 = box_distance2(x, nodes_[n.first].lo, nodes_[n.first].hi);
    const double d1 = box_distance2(x, nodes_[n.first + 1].lo, nodes_[n.first + 1].hi);
    if (d0 <= d1) stack[top++] = n.first + 1, stack[top++] = n.first;
    else stack[top++] = n.first, stack[top++] = n.first + 1;
  }
  return best;
}

}  // namespace spate
