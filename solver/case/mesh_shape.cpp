// Meshes as shapes (shape.hpp), read with VTK's readers for the file formats; the nearest point of
// the surface from a bounding-volume hierarchy over the triangles (triangle_tree.hpp says why not
// VTK's cell locator).
// spate's own code here only merges coincident points and checks that the triangles close a
// volume with outward normals, which no VTK filter reports as one verdict.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <unordered_map>

#include <fmt/format.h>

#include <vtkCellArray.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkDelaunay3D.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkOBJReader.h>
#include <vtkObject.h>
#include <vtkPLYReader.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkSTLReader.h>
#include <vtkSmartPointer.h>
#include <vtkTriangleFilter.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>

#include "shape.hpp"
#include "point3.hpp"
#include "triangle_tree.hpp"

namespace spate {

namespace {

using P3 = std::array<double, 3>;
using Tri = std::array<long long, 3>;  // point numbers (TriangleTree's)

constexpr double kPi = 3.14159265358979323846;
constexpr std::uintmax_t kMaxMeshFileBytes = 2ull << 30;  // 2 GiB

using point3::cross, point3::dot, point3::norm, point3::sub;

std::string point_text(const P3& p) { return fmt::format("({:.6g}, {:.6g}, {:.6g})", p[0], p[1], p[2]); }

// Triangles over merged points: what the checks and the distance work on.
struct TriangleMesh {
  std::vector<P3> points;
  std::vector<Tri> triangles;
};

// The triangles of a VTK polydata (polygons and strips triangulated; lines and vertices dropped),
// with exactly coincident points merged (STL stores every triangle's corners separately).
TriangleMesh triangles_of(vtkPolyData* input) {
  vtkNew<vtkTriangleFilter> tri;
  tri->SetInputData(input);
  tri->PassLinesOff();
  tri->PassVertsOff();
  tri->Update();
  vtkPolyData* out = tri->GetOutput();
  TriangleMesh m;
  std::map<P3, vtkIdType> index;
  std::vector<vtkIdType> merged(static_cast<std::size_t>(out->GetNumberOfPoints()));
  for (vtkIdType k = 0; k < out->GetNumberOfPoints(); ++k) {
    P3 p;
    out->GetPoint(k, p.data());
    auto [it, fresh] = index.emplace(p, static_cast<vtkIdType>(m.points.size()));
    if (fresh) m.points.push_back(p);
    merged[static_cast<std::size_t>(k)] = it->second;
  }
  vtkCellArray* polys = out->GetPolys();
  vtkNew<vtkIdList> ids;
  polys->InitTraversal();
  while (polys->GetNextCell(ids)) {
    if (ids->GetNumberOfIds() != 3) continue;
    m.triangles.push_back({merged[ids->GetId(0)], merged[ids->GetId(1)], merged[ids->GetId(2)]});
  }
  return m;
}

void place(TriangleMesh& m, const MeshPlacement& at) {
  const double rx = at.rotate[0] * kPi / 180, ry = at.rotate[1] * kPi / 180, rz = at.rotate[2] * kPi / 180;
  for (P3& p : m.points) {
    for (int a = 0; a < 3; ++a) p[a] *= at.scale[a];
    // About x, then y, then z (right-handed, angles counter-clockwise seen from the axis' tip).
    p = {p[0], std::cos(rx) * p[1] - std::sin(rx) * p[2], std::sin(rx) * p[1] + std::cos(rx) * p[2]};
    p = {std::cos(ry) * p[0] + std::sin(ry) * p[2], p[1], -std::sin(ry) * p[0] + std::cos(ry) * p[2]};
    p = {std::cos(rz) * p[0] - std::sin(rz) * p[1], std::sin(rz) * p[0] + std::cos(rz) * p[1], p[2]};
    for (int a = 0; a < 3; ++a) p[a] += at.translate[a];
  }
  // A mirroring scale turns the surface inside out: flip the triangles back.
  if (at.scale[0] * at.scale[1] * at.scale[2] < 0)
    for (Tri& t : m.triangles) std::swap(t[1], t[2]);
}

// The checks the signed distance needs: triangles, none degenerate, every edge shared by exactly
// two triangles that run it in opposite directions (closed, consistently oriented), and a positive
// enclosed volume (normals outward). The message names the first offence.
void check_closed(const TriangleMesh& m, const std::string& what) {
  if (m.triangles.empty()) throw ShapeError(what + " has no triangles (empty, or not a surface mesh)");
  if (static_cast<long long>(m.triangles.size()) > kMaxMeshTriangles)
    throw ShapeError(fmt::format("{} has {} triangles; at most {} (decimate it, e.g. ParaView's Decimate filter)", what,
                                 m.triangles.size(), kMaxMeshTriangles));
  P3 lo = m.points[0], hi = lo;
  for (const P3& p : m.points)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  const double diagonal = norm(sub(hi, lo));
  std::size_t degenerate = 0, first = 0;
  for (std::size_t k = 0; k < m.triangles.size(); ++k) {
    const Tri& t = m.triangles[k];
    const double twice_area = norm(cross(sub(m.points[t[1]], m.points[t[0]]), sub(m.points[t[2]], m.points[t[0]])));
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(twice_area > 1e-12 * diagonal * diagonal))
      if (degenerate++ == 0) first = k;
  }
  if (degenerate)
    throw ShapeError(fmt::format("{} has {} degenerate triangles (no area; the first, triangle {}, at {})", what, degenerate, first,
                                 point_text(m.points[m.triangles[first][0]])));
  // Directed edge (a, b) -> how often; a closed oriented surface has each once, and (b, a) once.
  std::map<std::pair<vtkIdType, vtkIdType>, int> directed;
  for (const Tri& t : m.triangles)
    for (int e = 0; e < 3; ++e) ++directed[{t[e], t[(e + 1) % 3]}];
  std::size_t open = 0, flipped = 0;
  P3 open_at{}, flipped_at{};
  for (const auto& [edge, count] : directed) {
    const auto back = directed.find({edge.second, edge.first});
    const int reverse = back == directed.end() ? 0 : back->second;
    if (count > 1) {
      if (flipped++ == 0) flipped_at = m.points[edge.first];
    } else if (reverse == 0) {
      if (open++ == 0) open_at = m.points[edge.first];
    }
  }
  if (open)
    throw ShapeError(fmt::format("{} is not closed: {} edges belong to one triangle only (the first at {}); a solid, a tank or a "
                                 "fluid region must be a closed surface",
                                 what, open, point_text(open_at)));
  if (flipped)
    throw ShapeError(fmt::format("{} has inconsistent normals (or is not manifold): {} edges run the same way in two triangles "
                                 "(the first at {})",
                                 what, flipped, point_text(flipped_at)));
  double volume = 0;  // divergence theorem: sum of the signed tetrahedra on the origin
  for (const Tri& t : m.triangles) volume += dot(m.points[t[0]], cross(m.points[t[1]], m.points[t[2]])) / 6.0;
  if (!(volume > 0))
    throw ShapeError(fmt::format("{} is inside out: its normals point inward (enclosed volume {:.6g} m3); flip its triangles", what,
                                 volume));
}

// The signed distance to a closed triangle mesh: the nearest point from the triangles' hierarchy,
// the sign from the angle-weighted pseudo-normal of the feature it lies on (face, edge or vertex;
// Baerentzen & Aanaes 2005), which is exact for a closed, consistently oriented surface: the
// nearest point's face normal alone misjudges points near sharp edges.
class MeshShape final : public Shape {
 public:
  MeshShape(const TriangleMesh& m, int dim, const std::string& name, const std::string& definition)
      : dim_(dim), points_(m.points), triangles_(m.triangles), tree_(points_, triangles_) {
    // Pseudo-normals: faces' unit normals; an edge's, the sum of its two faces'; a vertex's, its
    // faces' weighted by their angles at it.
    face_normal_.resize(m.triangles.size());
    vertex_normal_.assign(m.points.size(), P3{0, 0, 0});
    for (std::size_t f = 0; f < m.triangles.size(); ++f) {
      const Tri& t = m.triangles[f];
      P3 n = cross(sub(m.points[t[1]], m.points[t[0]]), sub(m.points[t[2]], m.points[t[0]]));
      const double len = norm(n);
      for (double& v : n) v /= len;
      face_normal_[f] = n;
      for (int k = 0; k < 3; ++k) {
        const P3 u = sub(m.points[t[(k + 1) % 3]], m.points[t[k]]), w = sub(m.points[t[(k + 2) % 3]], m.points[t[k]]);
        const double angle = std::acos(std::clamp(dot(u, w) / (norm(u) * norm(w)), -1.0, 1.0));
        for (int a = 0; a < 3; ++a) vertex_normal_[t[k]][a] += angle * n[a];
      }
      for (int k = 0; k < 3; ++k) {
        P3& e = edge_normal_[edge_key(t[k], t[(k + 1) % 3])];
        for (int a = 0; a < 3; ++a) e[a] += n[a];
      }
    }
    P3 l = m.points[0], h = l;
    for (const P3& p : m.points)
      for (int a = 0; a < 3; ++a) l[a] = std::min(l[a], p[a]), h[a] = std::max(h[a], p[a]);
    double side_area = 0, total = 0;
    for (const Tri& t : m.triangles) {
      const P3 n = cross(sub(m.points[t[1]], m.points[t[0]]), sub(m.points[t[2]], m.points[t[0]]));
      total += 0.5 * norm(n);
      if (std::fabs(n[2]) < 1e-9 * norm(n)) side_area += 0.5 * norm(n);
    }
    lo = l, hi = h;
    mid_z_ = 0.5 * (l[2] + h[2]);
    depth_ = h[2] - l[2];
    // 2D: the profile's perimeter is the prism's side area over its depth.
    area = dim == 2 ? side_area / depth_ : total;
    if (dim == 2) lo[2] = hi[2] = 0.0;
    signature = definition;
    triangles = static_cast<long long>(m.triangles.size());
    description = fmt::format("{}: {} triangles, {} points, bounding box {} to {}", name, m.triangles.size(), m.points.size(),
                              point_text(l), point_text(h));
  }
  double distance(const double x[3], double normal[3]) const override {
    const double at[3] = {x[0], x[1], dim_ == 2 ? mid_z_ : x[2]};
    const TriangleTree::Nearest nearest = tree_.nearest({at[0], at[1], at[2]});
    const P3& c = nearest.point;
    const std::size_t cell = nearest.triangle;
    const double d2 = nearest.distance2;
    const P3 r{at[0] - c[0], at[1] - c[1], at[2] - c[2]};
    const P3 pseudo = pseudo_normal(cell, c);
    const double d = std::sqrt(d2);
    const double sign = dot(r, pseudo) < 0 ? -1.0 : 1.0;
    P3 n = d > 1e-12 * (depth_ + norm(sub(hi, lo))) ? P3{sign * r[0] / d, sign * r[1] / d, sign * r[2] / d} : face_normal_[cell];
    if (dim_ == 2) n[2] = 0.0;
    const double len = norm(n);
    for (int a = 0; a < dim_; ++a) normal[a] = len > 0 ? n[a] / len : 0.0;
    return sign * d;
  }
  void surface(std::vector<std::array<double, 3>>& points, std::vector<std::vector<long long>>& polygons) const override {
    const long long base = static_cast<long long>(points.size());
    points.insert(points.end(), points_.begin(), points_.end());
    for (const Tri& t : triangles_) polygons.push_back({base + t[0], base + t[1], base + t[2]});
  }
  double depth() const { return depth_; }

 private:
  static std::uint64_t edge_key(vtkIdType a, vtkIdType b) {
    if (a > b) std::swap(a, b);
    return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint64_t>(b);
  }
  // The pseudo-normal of the feature of triangle f that holds point c: a vertex, an edge or the face,
  // by c's barycentric coordinates.
  P3 pseudo_normal(std::size_t f, const P3& c) const {
    const Tri& t = triangles_[f];
    const P3 &a = points_[t[0]], &b = points_[t[1]], &q = points_[t[2]];
    const P3 e0 = sub(b, a), e1 = sub(q, a), e2 = sub(c, a);
    const double d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1), d20 = dot(e2, e0), d21 = dot(e2, e1);
    const double den = d00 * d11 - d01 * d01;
    const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den, u = 1.0 - v - w;
    const double eps = 1e-9;
    const double bary[3] = {u, v, w};
    int zeros = 0, last_nonzero = -1, zero_at = -1;
    for (int k = 0; k < 3; ++k) {
      if (bary[k] <= eps) ++zeros, zero_at = k;
      else last_nonzero = k;
    }
    if (zeros >= 2) return vertex_normal_[t[last_nonzero]];                                  // at a vertex
    if (zeros == 1) return edge_normal_.at(edge_key(t[(zero_at + 1) % 3], t[(zero_at + 2) % 3]));  // on the edge opposite
    return face_normal_[f];
  }

  int dim_;
  double mid_z_ = 0.0, depth_ = 0.0;
  std::vector<P3> points_;
  std::vector<Tri> triangles_;
  std::vector<P3> face_normal_, vertex_normal_;
  std::unordered_map<std::uint64_t, P3> edge_normal_;
  TriangleTree tree_;  // after points_ and triangles_, which it reads
};

std::uint64_t file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a, 64 bits
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    for (std::streamsize k = 0; k < in.gcount(); ++k) h = (h ^ static_cast<unsigned char>(buffer[k])) * 1099511628211ull;
  }
  return h;
}

vtkSmartPointer<vtkPolyData> read_polydata(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  // The readers report a bad file on VTK's output window, not to the caller: quiet them and judge
  // by what they produced.
  const bool warnings = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  vtkSmartPointer<vtkPolyData> out;
  auto run = [&](auto reader) {
    reader->SetFileName(path.c_str());
    reader->Update();
    out = reader->GetOutput();
  };
  if (ext == ".stl") run(vtkSmartPointer<vtkSTLReader>::New());
  else if (ext == ".obj") run(vtkSmartPointer<vtkOBJReader>::New());
  else if (ext == ".ply") run(vtkSmartPointer<vtkPLYReader>::New());
  else if (ext == ".vtp") run(vtkSmartPointer<vtkXMLPolyDataReader>::New());
  else if (ext == ".vtk") run(vtkSmartPointer<vtkPolyDataReader>::New());
  vtkObject::SetGlobalWarningDisplay(warnings);
  if (ext != ".stl" && ext != ".obj" && ext != ".ply" && ext != ".vtp" && ext != ".vtk")
    throw ShapeError(fmt::format("'{}': unknown mesh format '{}' (spate reads .stl, .obj, .ply, .vtp and legacy .vtk polydata)", path,
                                 ext));
  return out;
}

}  // namespace

bool mesh_support() { return true; }

ShapePtr load_mesh(const std::string& path, const MeshPlacement& placement, int dim) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw ShapeError(fmt::format("'{}': no such mesh file", path));
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) throw ShapeError(fmt::format("'{}': cannot read its size: {}", path, ec.message()));
  if (bytes > kMaxMeshFileBytes)
    throw ShapeError(fmt::format("'{}' is {:.1f} GiB; at most 2 GiB (decimate the mesh)", path, bytes / double(1u << 30)));
  if (!std::ifstream(path)) throw ShapeError(fmt::format("'{}': cannot be opened for reading", path));
  vtkSmartPointer<vtkPolyData> poly = read_polydata(path);
  TriangleMesh m = poly ? triangles_of(poly) : TriangleMesh{};
  const std::string what = fmt::format("mesh '{}'", path);
  place(m, placement);
  check_closed(m, what);
  const std::string definition =
      fmt::format("mesh {:016x} ({} bytes) scale [{:.17g}, {:.17g}, {:.17g}] rotate [{:.17g}, {:.17g}, {:.17g}] translate [{:.17g}, "
                  "{:.17g}, {:.17g}]",
                  file_hash(path), bytes, placement.scale[0], placement.scale[1], placement.scale[2], placement.rotate[0],
                  placement.rotate[1], placement.rotate[2], placement.translate[0], placement.translate[1], placement.translate[2]);
  auto shape = std::make_shared<MeshShape>(m, dim, what, definition);
  if (dim == 2 && !(shape->depth() > 0))
    throw ShapeError(what + " is flat in z: a 2D case cuts a mesh at its middle z, so it must be a prism along z");
  return shape;
}

ShapePtr make_polyhedron(const std::vector<P3>& points) {
  if (points.size() < 4) throw ShapeError("a polyhedron needs at least 4 vertices");
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  for (const P3& p : points) pts->InsertNextPoint(p.data());
  vtkNew<vtkPolyData> cloud;
  cloud->SetPoints(pts);
  vtkNew<vtkDelaunay3D> hull;  // its tetrahedra fill the convex hull; their outer faces bound it
  hull->SetInputData(cloud);
  vtkNew<vtkDataSetSurfaceFilter> surface;
  surface->SetInputConnection(hull->GetOutputPort());
  surface->Update();
  TriangleMesh m = triangles_of(surface->GetOutput());
  if (m.triangles.empty()) throw ShapeError("the vertices span no volume (all in one plane?)");
  // A convex hull: each face turned to have the centroid on its inner side.
  P3 centre{0, 0, 0};
  for (const P3& p : m.points)
    for (int a = 0; a < 3; ++a) centre[a] += p[a] / static_cast<double>(m.points.size());
  for (Tri& t : m.triangles)
    if (dot(cross(sub(m.points[t[1]], m.points[t[0]]), sub(m.points[t[2]], m.points[t[0]])), sub(m.points[t[0]], centre)) < 0)
      std::swap(t[1], t[2]);
  check_closed(m, "the polyhedron");
  std::string definition = "polyhedron";
  for (const P3& p : points) definition += fmt::format(" [{:.17g}, {:.17g}, {:.17g}]", p[0], p[1], p[2]);
  return std::make_shared<MeshShape>(m, 3, fmt::format("polyhedron of {} vertices", points.size()), definition);
}

}  // namespace spate
