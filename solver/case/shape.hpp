#pragma once
// Solids and fluid regions beyond axis-aligned boxes (issue 31): a shape answers the signed
// distance from a point to its surface (negative inside) and the outward normal there. The
// generator fills a fluid region with the lattice sites inside it, and shells a solid with the
// sites within `wall_layers` dp under its surface; by default they stay on the lattice, a
// staircase under a slanted or curved face (generator.cpp says why), or with `wall_particles:
// surface` lie in layers along the surface (surface_layers below).
// Primitives are exact; meshes (STL, OBJ, PLY, VTK/VTP) are read and
// checked with VTK (mesh_shape.cpp), in builds that have it.
#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace spate {

// A shape that cannot be made: the message says why (the loader adds the file and key).
struct ShapeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Shape {
 public:
  virtual ~Shape() = default;
  // Signed distance from x to the surface [m], negative inside; `normal`: the unit outward normal
  // of the nearest surface point (the distance's gradient). 2D shapes read and write (x, y) only.
  virtual double distance(const double x[3], double normal[3]) const = 0;
  // The surface as polygons over points (a mesh's triangles; the primitives tessellated finely),
  // for drawing it (in situ, in ParaView). 2D shapes: their outline as one polygon at z = 0, or a
  // mesh's prism.
  virtual void surface(std::vector<std::array<double, 3>>& points, std::vector<std::vector<long long>>& polygons) const = 0;

  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};  // bounding box
  double area = 0.0;        // surface area [m2]; 2D: the perimeter [m] (per metre of depth)
  std::string signature;    // what defines it, exactly, for the geometry hash (a mesh: its file's hash)
  std::string description;  // one line for `spate info` (a mesh: file, triangles, bounding box)
  long long triangles = 0;  // a mesh's (or polyhedron's) triangles; 0 for the exact primitives
};
using ShapePtr = std::shared_ptr<const Shape>;

// Wall particles that follow a shape's surface (a solid's or a shaped tank's `wall_particles:
// surface`): `layers` layers, layer k on the level set at (k + 1/2) dp behind the surface (inside
// the shape, or outside it when `outside`: a container's walls). 2D: each contour resampled at even
// arc-length spacing as near dp as a whole number of points allows (surface_layers.cpp), points at
// z = 0. 3D: dp^-2 points per square metre of each level set, spread evenly (surface_layers_3d.cpp).
std::vector<std::array<double, 3>> surface_layers_2d(const Shape& shape, double dp, int layers, bool outside);
std::vector<std::array<double, 3>> surface_layers_3d(const Shape& shape, double dp, int layers, bool outside);
inline std::vector<std::array<double, 3>> surface_layers(const Shape& shape, double dp, int layers, bool outside, int dim) {
  return dim == 2 ? surface_layers_2d(shape, dp, layers, outside) : surface_layers_3d(shape, dp, layers, outside);
}

// The surface of a shape as VTK XML polydata (a .vtp file's text; ASCII, readable by ParaView).
std::string surface_vtp(const Shape& shape);
// The same of a box (its six faces).
std::string box_surface_vtp(const std::array<double, 3>& lo, const std::array<double, 3>& hi);
// Points with an unsigned integer point array `id`, as VTK XML polydata (the start positions of a
// moving solid's particles, which the in-situ pipeline fits its motion to).
std::string points_vtp(const std::vector<std::array<double, 3>>& points, const std::vector<std::uint32_t>& ids);

// An axis-aligned box (2D: rectangle) from lo to hi.
ShapePtr make_box(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int dim);
// Points along a 3D shape's sharp edges (where its faces meet at more than 20 degrees, and any
// edge of a single face), at most `spacing` apart, their ends left out: floating bodies' contact
// spheres, so that an edge crossing another edge or a face is seen (ShapeContacts).
std::vector<std::array<double, 3>> sharp_edge_points(const Shape& shape, double spacing);
// A disc (2D) or sphere (3D).
ShapePtr make_ball(const std::array<double, 3>& centre, double radius, int dim);
// A capped circular cylinder (3D) of the given axis (unit vector), radius and length, centred at
// `centre`.
ShapePtr make_cylinder(const std::array<double, 3>& centre, const std::array<double, 3>& axis, double radius, double length);
// A simple polygon (2D; vertices in either order, not self-intersecting).
ShapePtr make_polygon(const std::vector<std::array<double, 2>>& vertices);

// A mesh file's placement: scaled about the origin, rotated about x, then y, then z [degrees],
// then translated.
struct MeshPlacement {
  std::array<double, 3> scale{1, 1, 1};
  std::array<double, 3> rotate{0, 0, 0};
  std::array<double, 3> translate{0, 0, 0};
};
// Whether this build reads meshes (VTK found at configure time).
bool mesh_support();
// A closed, consistently oriented triangle mesh read from `path` (STL, OBJ, PLY, VTP, VTK). Throws
// ShapeError when the file is missing or unreadable, has no triangles, is not closed, has
// inconsistent or inward normals, degenerate triangles or more than kMaxMeshTriangles. In 2D the
// mesh is cut by the plane z = (its middle z): it must be a prism along z (an extruded profile).
ShapePtr load_mesh(const std::string& path, const MeshPlacement& placement, int dim);
// The convex hull of points (3D).
ShapePtr make_polyhedron(const std::vector<std::array<double, 3>>& points);
inline constexpr long long kMaxMeshTriangles = 5'000'000;

}  // namespace spate
