#include "shape.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

namespace spate {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Any unit vector perpendicular to the unit vector u.
void perpendicular(const double u[3], double out[3]) {
  const int k = std::fabs(u[0]) < 0.9 ? 0 : 1;  // the axis least aligned with u
  double e[3] = {0, 0, 0};
  e[k] = 1.0;
  const double dot = e[0] * u[0] + e[1] * u[1] + e[2] * u[2];
  double len = 0;
  for (int a = 0; a < 3; ++a) out[a] = e[a] - dot * u[a], len += out[a] * out[a];
  for (int a = 0; a < 3; ++a) out[a] /= std::sqrt(len);
}

// Exact (the signature) or short (the description).
std::string vec_text(const std::array<double, 3>& v, int dim, bool exact = true) {
  std::string s = "[";
  for (int a = 0; a < dim; ++a) s += exact ? fmt::format("{}{:.17g}", a ? ", " : "", v[a]) : fmt::format("{}{:g}", a ? ", " : "", v[a]);
  return s + "]";
}

class Ball final : public Shape {
 public:
  Ball(const std::array<double, 3>& centre, double radius, int dim) : c_(centre), r_(radius), dim_(dim) {
    for (int a = 0; a < 3; ++a) lo[a] = a < dim ? c_[a] - r_ : 0.0, hi[a] = a < dim ? c_[a] + r_ : 0.0;
    area = dim == 2 ? 2.0 * kPi * r_ : 4.0 * kPi * r_ * r_;
    signature = fmt::format("{} centre {} radius {:.17g}", dim == 2 ? "disc" : "sphere", vec_text(c_, dim), r_);
    description = fmt::format("{} of radius {:g} m at {}", dim == 2 ? "disc" : "sphere", r_, vec_text(c_, dim, false));
  }
  double distance(const double x[3], double normal[3]) const override {
    double w[3] = {0, 0, 0}, s = 0;
    for (int a = 0; a < dim_; ++a) w[a] = x[a] - c_[a], s += w[a] * w[a];
    s = std::sqrt(s);
    for (int a = 0; a < dim_; ++a) normal[a] = s > 0 ? w[a] / s : (a == dim_ - 1 ? 1.0 : 0.0);
    return s - r_;
  }
  void surface(std::vector<std::array<double, 3>>& points, std::vector<std::vector<long long>>& polygons) const override {
    constexpr int kAround = 96, kRings = 48;
    if (dim_ == 2) {
      polygons.emplace_back();
      for (int k = 0; k < kAround; ++k) {
        polygons.back().push_back(static_cast<long long>(points.size()));
        points.push_back({c_[0] + r_ * std::cos(2 * kPi * k / kAround), c_[1] + r_ * std::sin(2 * kPi * k / kAround), 0.0});
      }
      return;
    }
    // Rings of latitude between the poles; quads between rings, triangles at the poles.
    const long long base = static_cast<long long>(points.size());
    points.push_back({c_[0], c_[1], c_[2] - r_});
    for (int i = 1; i < kRings; ++i) {
      const double theta = kPi * i / kRings;
      for (int k = 0; k < kAround; ++k) {
        const double phi = 2 * kPi * k / kAround;
        points.push_back({c_[0] + r_ * std::sin(theta) * std::cos(phi), c_[1] + r_ * std::sin(theta) * std::sin(phi), c_[2] - r_ * std::cos(theta)});
      }
    }
    points.push_back({c_[0], c_[1], c_[2] + r_});
    auto at = [&](int ring, int k) { return base + 1 + static_cast<long long>(ring - 1) * kAround + (k % kAround); };
    const long long top = static_cast<long long>(points.size()) - 1;
    for (int k = 0; k < kAround; ++k) {
      polygons.push_back({base, at(1, k + 1), at(1, k)});
      for (int i = 1; i + 1 < kRings; ++i) polygons.push_back({at(i, k), at(i, k + 1), at(i + 1, k + 1), at(i + 1, k)});
      polygons.push_back({at(kRings - 1, k), at(kRings - 1, k + 1), top});
    }
  }

 private:
  std::array<double, 3> c_;
  double r_;
  int dim_;
};

// An axis-aligned box (2D: a rectangle): a box solid's surface where something needs its distance
// (floating bodies' contact, sim/rigid_bodies.cpp); the generator shells box solids itself.
class Box final : public Shape {
 public:
  Box(const std::array<double, 3>& lo_corner, const std::array<double, 3>& hi_corner, int dim) : dim_(dim) {
    lo = lo_corner, hi = hi_corner;
    for (int a = dim; a < 3; ++a) lo[a] = hi[a] = 0.0;
    area = dim == 2 ? 2 * (hi[0] - lo[0] + hi[1] - lo[1])
                    : 2 * ((hi[0] - lo[0]) * (hi[1] - lo[1]) + (hi[1] - lo[1]) * (hi[2] - lo[2]) + (hi[2] - lo[2]) * (hi[0] - lo[0]));
    signature = fmt::format("box {} {}", vec_text(lo, dim), vec_text(hi, dim));
    description = fmt::format("box from {} to {}", vec_text(lo, dim, false), vec_text(hi, dim, false));
  }
  // Outside: the distance to the nearest point of the box; inside: minus that to the nearest face.
  double distance(const double x[3], double normal[3]) const override {
    double out[3] = {0, 0, 0}, outside = 0.0, deepest = -1e300;
    int face = 0;
    for (int a = 0; a < dim_; ++a) {
      const double below = lo[a] - x[a], above = x[a] - hi[a];
      out[a] = below > 0 ? -below : above > 0 ? above : 0.0;
      outside += out[a] * out[a];
      const double q = std::max(below, above);  // <= 0 inside: minus the distance to this axis' nearer face
      if (q > deepest) deepest = q, face = above >= below ? a + 1 : -(a + 1);
    }
    for (int a = 0; a < dim_; ++a) normal[a] = 0.0;
    if (outside > 0) {
      const double s = std::sqrt(outside);
      for (int a = 0; a < dim_; ++a) normal[a] = out[a] / s;
      return s;
    }
    normal[std::abs(face) - 1] = face > 0 ? 1.0 : -1.0;
    return deepest;
  }
  void surface(std::vector<std::array<double, 3>>& points, std::vector<std::vector<long long>>& polygons) const override {
    const long long base = static_cast<long long>(points.size());
    if (dim_ == 2) {
      points.insert(points.end(), {{lo[0], lo[1], 0.0}, {hi[0], lo[1], 0.0}, {hi[0], hi[1], 0.0}, {lo[0], hi[1], 0.0}});
      polygons.push_back({base, base + 1, base + 2, base + 3});
      return;
    }
    for (int k = 0; k < 8; ++k) points.push_back({k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]});
    // Corners numbered by bits x, y, z; each face counter-clockwise seen from outside.
    for (const auto& f : {std::array<int, 4>{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}})
      polygons.push_back({base + f[0], base + f[1], base + f[2], base + f[3]});
  }

 private:
  int dim_;
};

class Cylinder final : public Shape {
 public:
  Cylinder(const std::array<double, 3>& centre, const std::array<double, 3>& axis, double radius, double length)
      : c_(centre), u_(axis), r_(radius), half_(0.5 * length) {
    for (int a = 0; a < 3; ++a) {
      const double reach = std::fabs(u_[a]) * half_ + r_ * std::sqrt(std::max(0.0, 1.0 - u_[a] * u_[a]));
      lo[a] = c_[a] - reach, hi[a] = c_[a] + reach;
    }
    area = 2.0 * kPi * r_ * length + 2.0 * kPi * r_ * r_;
    signature = fmt::format("cylinder centre {} axis {} radius {:.17g} length {:.17g}", vec_text(c_, 3), vec_text(u_, 3), r_, length);
    description = fmt::format("cylinder of radius {:g} m and length {:g} m at {} along {}", r_, length, vec_text(c_, 3, false),
                              vec_text(u_, 3, false));
  }
  // The capped cylinder's exact distance: radial excess qr = s - r, axial excess qa = |t| - L/2.
  double distance(const double x[3], double normal[3]) const override {
    double w[3], t = 0;
    for (int a = 0; a < 3; ++a) w[a] = x[a] - c_[a], t += w[a] * u_[a];
    double e[3], s = 0;
    for (int a = 0; a < 3; ++a) e[a] = w[a] - t * u_[a], s += e[a] * e[a];
    s = std::sqrt(s);
    if (s > 0) {
      for (double& v : e) v /= s;
    } else {
      perpendicular(u_.data(), e);
    }
    const double side = t >= 0 ? 1.0 : -1.0;
    const double qr = s - r_, qa = std::fabs(t) - half_;
    double d, nr = 0, na = 0;
    if (qr <= 0 && qa <= 0) {  // inside: the nearer of the mantle and the caps
      d = std::max(qr, qa);
      (qr > qa ? nr : na) = 1.0;
    } else if (qr > 0 && qa > 0) {  // beyond a rim: the distance to the circle
      d = std::hypot(qr, qa);
      nr = qr / d, na = qa / d;
    } else {
      d = std::max(qr, qa);
      (qr > 0 ? nr : na) = 1.0;
    }
    for (int a = 0; a < 3; ++a) normal[a] = nr * e[a] + na * side * u_[a];
    return d;
  }
  void surface(std::vector<std::array<double, 3>>& points, std::vector<std::vector<long long>>& polygons) const override {
    constexpr int kAround = 96;
    double e1[3], e2[3];
    perpendicular(u_.data(), e1);
    e2[0] = u_[1] * e1[2] - u_[2] * e1[1], e2[1] = u_[2] * e1[0] - u_[0] * e1[2], e2[2] = u_[0] * e1[1] - u_[1] * e1[0];
    const long long base = static_cast<long long>(points.size());
    for (int end = 0; end < 2; ++end)
      for (int k = 0; k < kAround; ++k) {
        const double c = std::cos(2 * kPi * k / kAround), s = std::sin(2 * kPi * k / kAround), t = end ? half_ : -half_;
        points.push_back({c_[0] + r_ * (c * e1[0] + s * e2[0]) + t * u_[0], c_[1] + r_ * (c * e1[1] + s * e2[1]) + t * u_[1],
                          c_[2] + r_ * (c * e1[2] + s * e2[2]) + t * u_[2]});
      }
    std::vector<long long> bottom, top;
    for (int k = 0; k < kAround; ++k) {
      const long long a = base + k, b = base + (k + 1) % kAround;
      polygons.push_back({a, b, b + kAround, a + kAround});
      bottom.push_back(base + (kAround - k) % kAround);
      top.push_back(base + kAround + k);
    }
    polygons.push_back(bottom);
    polygons.push_back(top);
  }

 private:
  std::array<double, 3> c_, u_;
  double r_, half_;
};

class Polygon final : public Shape {
 public:
  explicit Polygon(std::vector<std::array<double, 2>> v) : v_(std::move(v)) {
    double twice_area = 0;
    for (std::size_t k = 0; k < v_.size(); ++k) {
      const auto& a = v_[k];
      const auto& b = v_[(k + 1) % v_.size()];
      twice_area += a[0] * b[1] - b[0] * a[1];
      area += std::hypot(b[0] - a[0], b[1] - a[1]);
    }
    if (twice_area < 0) std::reverse(v_.begin(), v_.end());  // counter-clockwise from here on
    lo = {v_[0][0], v_[0][1], 0}, hi = lo;
    for (auto& p : v_)
      for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    signature = "polygon";
    for (auto& p : v_) signature += fmt::format(" [{:.17g}, {:.17g}]", p[0], p[1]);
    description = fmt::format("polygon of {} vertices", v_.size());
  }
  double distance(const double x[3], double normal[3]) const override {
    double best = INFINITY, best_t = 0;
    std::size_t best_edge = 0;
    bool inside = false;
    for (std::size_t k = 0; k < v_.size(); ++k) {
      const auto& a = v_[k];
      const auto& b = v_[(k + 1) % v_.size()];
      const double ex = b[0] - a[0], ey = b[1] - a[1];
      const double t = std::clamp(((x[0] - a[0]) * ex + (x[1] - a[1]) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
      const double dx = x[0] - (a[0] + t * ex), dy = x[1] - (a[1] + t * ey);
      const double d2 = dx * dx + dy * dy;
      if (d2 < best) best = d2, best_edge = k, best_t = t;
      // Crossing number along +x (half-open in y, so a vertex counts once).
      if ((a[1] > x[1]) != (b[1] > x[1]) && x[0] < a[0] + (x[1] - a[1]) * ex / ey) inside = !inside;
    }
    const auto& a = v_[best_edge];
    const auto& b = v_[(best_edge + 1) % v_.size()];
    const double d = std::sqrt(best);
    const double px = a[0] + best_t * (b[0] - a[0]), py = a[1] + best_t * (b[1] - a[1]);
    if (d > 1e-12 * (hi[0] - lo[0] + hi[1] - lo[1])) {
      const double s = inside ? -1.0 : 1.0;
      normal[0] = s * (x[0] - px) / d, normal[1] = s * (x[1] - py) / d;
    } else {  // on the edge: its outward normal (counter-clockwise: the right-hand side)
      const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
      normal[0] = (b[1] - a[1]) / len, normal[1] = -(b[0] - a[0]) / len;
    }
    return inside ? -d : d;
  }
  void surface(std::vector<std::array<double, 3>>& points, std::vector<std::vector<long long>>& polygons) const override {
    polygons.emplace_back();
    for (const auto& p : v_) {
      polygons.back().push_back(static_cast<long long>(points.size()));
      points.push_back({p[0], p[1], 0.0});
    }
  }

 private:
  std::vector<std::array<double, 2>> v_;
};

}  // namespace

namespace {
std::string polydata_vtp(const std::vector<std::array<double, 3>>& points, const std::vector<std::vector<long long>>& polygons) {
  std::string s = fmt::format(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      "<PolyData>\n<Piece NumberOfPoints=\"{}\" NumberOfPolys=\"{}\">\n<Points>\n"
      "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
      points.size(), polygons.size());
  for (const auto& p : points) s += fmt::format("{:.9g} {:.9g} {:.9g}\n", p[0], p[1], p[2]);
  s += "</DataArray>\n</Points>\n<Polys>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& poly : polygons) {
    for (long long v : poly) s += fmt::format("{} ", v);
    s += "\n";
  }
  s += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  long long offset = 0;
  for (const auto& poly : polygons) s += fmt::format("{}\n", offset += static_cast<long long>(poly.size()));
  s += "</DataArray>\n</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  return s;
}
}  // namespace

std::string surface_vtp(const Shape& shape) {
  std::vector<std::array<double, 3>> points;
  std::vector<std::vector<long long>> polygons;
  shape.surface(points, polygons);
  return polydata_vtp(points, polygons);
}

std::string box_surface_vtp(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  std::vector<std::array<double, 3>> points;
  for (int k = 0; k < 8; ++k) points.push_back({k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]});
  // Corner k has bit a set where it is on the upper side along axis a; faces counter-clockwise from outside.
  const std::vector<std::vector<long long>> faces = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  return polydata_vtp(points, faces);
}

std::string points_vtp(const std::vector<std::array<double, 3>>& points, const std::vector<std::uint32_t>& ids) {
  std::string s = fmt::format(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
      "<PolyData>\n<Piece NumberOfPoints=\"{}\">\n<PointData>\n<DataArray type=\"UInt32\" Name=\"id\" format=\"ascii\">\n",
      points.size());
  for (const std::uint32_t id : ids) s += fmt::format("{}\n", id);
  s += "</DataArray>\n</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const auto& p : points) s += fmt::format("{:.9g} {:.9g} {:.9g}\n", p[0], p[1], p[2]);
  s += "</DataArray>\n</Points>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  return s;
}

ShapePtr make_ball(const std::array<double, 3>& centre, double radius, int dim) {
  if (!(radius > 0)) throw ShapeError("the radius must be > 0");
  return std::make_shared<Ball>(centre, radius, dim);
}

ShapePtr make_box(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int dim) { return std::make_shared<Box>(lo, hi, dim); }

ShapePtr make_cylinder(const std::array<double, 3>& centre, const std::array<double, 3>& axis, double radius, double length) {
  if (!(radius > 0)) throw ShapeError("the radius must be > 0");
  if (!(length > 0)) throw ShapeError("the length must be > 0");
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  if (!(n > 0)) throw ShapeError("the axis must be a non-zero vector");
  return std::make_shared<Cylinder>(centre, std::array<double, 3>{axis[0] / n, axis[1] / n, axis[2] / n}, radius, length);
}

ShapePtr make_polygon(const std::vector<std::array<double, 2>>& vertices) {
  if (vertices.size() < 3) throw ShapeError("a polygon needs at least 3 vertices");
  // Simple: no two edges that do not share a vertex may cross (or touch).
  const std::size_t n = vertices.size();
  auto orient = [](const std::array<double, 2>& a, const std::array<double, 2>& b, const std::array<double, 2>& c) {
    const double v = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    return (v > 0) - (v < 0);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const auto &a = vertices[i], &b = vertices[(i + 1) % n];
    if (a == b) throw ShapeError(fmt::format("vertices {} and {} coincide", i, (i + 1) % n));
    for (std::size_t j = i + 2; j < n; ++j) {
      if ((j + 1) % n == i) continue;  // adjacent through the closing edge
      const auto &c = vertices[j], &d = vertices[(j + 1) % n];
      if (orient(a, b, c) * orient(a, b, d) <= 0 && orient(c, d, a) * orient(c, d, b) <= 0)
        throw ShapeError(fmt::format("edges {} and {} cross: the polygon must be simple", i, j));
    }
  }
  return std::make_shared<Polygon>(vertices);
}

#ifndef SPATE_WITH_MESH
bool mesh_support() { return false; }
ShapePtr load_mesh(const std::string&, const MeshPlacement&, int) {
  throw ShapeError("this build of spate reads no meshes (VTK was not found when it was configured; see docs/building.md)");
}
ShapePtr make_polyhedron(const std::vector<std::array<double, 3>>&) {
  throw ShapeError("this build of spate makes no polyhedra (VTK was not found when it was configured; see docs/building.md)");
}
#endif

// Sharp edges: where two faces meet at more than kSharpAngle (a box's 12 edges; not the seams
// between a curved surface's facets). Edges are found by their end points' positions (a mesh's
// triangles may not share their vertices), rounded to 1e-9 m; each is sampled once, in the order
// of its first face, so the points are deterministic.
std::vector<std::array<double, 3>> sharp_edge_points(const Shape& shape, double spacing) {
  constexpr double kSharpAngle = 20.0 * M_PI / 180.0;
  std::vector<std::array<double, 3>> points;
  std::vector<std::vector<long long>> polygons;
  shape.surface(points, polygons);
  using Key = std::array<long long, 3>;
  auto key = [&](long long v) {
    return Key{std::llround(points[v][0] * 1e9), std::llround(points[v][1] * 1e9), std::llround(points[v][2] * 1e9)};
  };
  auto normal = [&](const std::vector<long long>& f) {
    std::array<double, 3> n{0, 0, 0};  // Newell's
    for (std::size_t k = 0; k < f.size(); ++k) {
      const auto &a = points[f[k]], &b = points[f[(k + 1) % f.size()]];
      n[0] += (a[1] - b[1]) * (a[2] + b[2]), n[1] += (a[2] - b[2]) * (a[0] + b[0]), n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    return l > 0 ? std::array<double, 3>{n[0] / l, n[1] / l, n[2] / l} : n;
  };
  struct Edge {
    long long a, b;
    std::array<double, 3> first_normal;
    bool sharp = false, seen_twice = false;
  };
  std::vector<Edge> edges;
  std::map<std::pair<Key, Key>, std::size_t> index;
  for (const auto& f : polygons) {
    const std::array<double, 3> n = normal(f);
    for (std::size_t k = 0; k < f.size(); ++k) {
      long long a = f[k], b = f[(k + 1) % f.size()];
      Key ka = key(a), kb = key(b);
      if (kb < ka) std::swap(ka, kb), std::swap(a, b);
      const auto [it, added] = index.try_emplace({ka, kb}, edges.size());
      if (added) {
        edges.push_back({a, b, n});
        continue;
      }
      Edge& e = edges[it->second];
      e.seen_twice = true;
      const double c = std::fabs(n[0] * e.first_normal[0] + n[1] * e.first_normal[1] + n[2] * e.first_normal[2]);
      e.sharp = e.sharp || c < std::cos(kSharpAngle);
    }
  }
  std::vector<std::array<double, 3>> out;
  for (const Edge& e : edges) {
    if (!e.sharp && e.seen_twice) continue;
    const auto &a = points[e.a], &b = points[e.b];
    const double length = std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
    const int pieces = static_cast<int>(std::ceil(length / spacing));
    for (int k = 1; k < pieces; ++k) {
      const double s = static_cast<double>(k) / pieces;
      out.push_back({a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])});
    }
  }
  return out;
}

}  // namespace spate
