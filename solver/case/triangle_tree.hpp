#pragma once
// The nearest point of a triangle mesh to a query point: a bounding-volume hierarchy over the
// triangles (median splits along the longest axis, four triangles a leaf), searched nearest box
// first and pruned by the best distance so far. A mesh shape's signed distance asks it for every
// lattice site near the surface and every wall particle placed on a level set (mesh_shape.cpp):
// VTK's static cell locator, which bins triangles by their bounding boxes, answered a cylindrical
// vessel's long side triangles in about 7 us a query (each bin holds every triangle that spans
// it, each copied out as a generic cell); the hierarchy answers in well under one. Read-only once
// built: safe from any number of threads.
#include <array>
#include <cstdint>
#include <vector>

namespace spate {

class TriangleTree {
 public:
  using P3 = std::array<double, 3>;
  TriangleTree(const std::vector<P3>& points, const std::vector<std::array<long long, 3>>& triangles);
  struct Nearest {
    P3 point{0, 0, 0};     // the nearest point of the surface
    double distance2 = 0;  // its squared distance from the query
    std::size_t triangle = 0;
  };
  // The nearest point of any triangle to x (of the nearest triangles, the first in the mesh's order).
  Nearest nearest(const P3& x) const;

 private:
  struct Node {
    P3 lo, hi;
    std::uint32_t first, count;  // a leaf: triangles order_[first, first + count); else count = 0,
                                 // children `first` and `first + 1`
  };
  std::uint32_t build(std::uint32_t begin, std::uint32_t end);
  void leaf_or_split(std::uint32_t node, std::uint32_t begin, std::uint32_t end);

  const std::vector<P3>& points_;
  const std::vector<std::array<long long, 3>>& triangles_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
  std::vector<P3> centroid_;
};

// The point of triangle (a, b, c) nearest to p (Ericson, "Real-Time Collision Detection", 5.1.5).
std::array<double, 3> closest_on_triangle(const std::array<double, 3>& p, const std::array<double, 3>& a, const std::array<double, 3>& b,
                                          const std::array<double, 3>& c);

}  // namespace spate
