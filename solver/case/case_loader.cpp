// YAML -> Case. Every key is read through a Section that remembers what it read, so anything left
// over is an unknown key, reported with the closest valid name.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "case.hpp"
#include "../io/input_file.hpp"

namespace spate {

namespace {

// A case file is a page of YAML; 16 MiB of it is not one (nor is /dev/zero).
constexpr std::size_t kLargestCaseFile = std::size_t{16} << 20;

// Edits (insert, delete, substitute, swap two neighbours) between a and b: the optimal string
// alignment distance, so that the usual typo `edn` is one edit from `end`.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> before(b.size() + 1), prev(b.size() + 1), row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      row[j] = std::min({prev[j] + 1, row[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) row[j] = std::min(row[j], before[j - 2] + 1);
    }
    std::swap(before, prev);
    std::swap(prev, row);
  }
  return prev[b.size()];
}

// What one read of a case shares between its sections.
struct ReadContext {
  std::string file;
  // Keys replaced by --set: their nodes carry positions inside the option's text, not in the file,
  // so messages about them quote the option instead of a line and column.
  std::vector<std::pair<std::string, std::string>> overridden;  // key path, the whole --set text
  // Every key the reader asked for, as a full path, so that an unknown key can be matched against
  // the keys of every section (a top-level `viscocity` suggests `fluid.viscosity`).
  std::set<std::string> valid_paths;
  struct Finished {
    YAML::Node node;
    std::string path;
    std::set<std::string> known;
  };
  std::vector<Finished> finished;  // checked for unknown keys once every section has been read

  const std::string* set_by(const std::string& path) const {
    for (auto& [key, assignment] : overridden)
      if (path == key || path.starts_with(key + ".") || path.starts_with(key + "[")) return &assignment;
    return nullptr;
  }
};

class Section {
 public:
  Section(YAML::Node node, std::string path, ReadContext& ctx) : node_(node), path_(std::move(path)), ctx_(ctx) {}

  [[noreturn]] void fail(const YAML::Node& at, const std::string& key, const std::string& what) const {
    std::ostringstream s;
    s << ctx_.file;
    const std::string* set = ctx_.set_by(full(key));
    // The position of the node at fault; none for a key missing at the top level (the document's
    // first line would only mislead) or a value given with --set.
    const bool top_level_map = path_.empty() && at.IsDefined() && at.is(node_);
    if (!set && !top_level_map && at && at.Mark().line >= 0) s << ':' << at.Mark().line + 1 << ':' << at.Mark().column + 1;
    s << ": key '" << full(key) << "'";
    if (set) s << " (from --set " << *set << ")";
    s << ": " << what;
    throw CaseError(s.str());
  }
  std::string full(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  bool has(const std::string& key) {
    remember(key);
    return node_[key].IsDefined() && !node_[key].IsNull();
  }
  YAML::Node raw(const std::string& key) {
    remember(key);
    return node_[key];
  }

  double number(const std::string& key, std::optional<double> fallback = {}) {
    YAML::Node n = raw(key);
    if (!n.IsDefined() || n.IsNull()) {
      if (fallback) return *fallback;
      fail(node_, key, "is required (a number)");
    }
    return to_number(n, key);
  }
  double to_number(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(n, key, "expected a number");
    try {
      const double v = n.as<double>();
      if (!std::isfinite(v)) fail(n, key, "expected a finite number, got '" + n.Scalar() + "'");
      return v;
    } catch (const YAML::Exception&) {
      fail(n, key, "expected a number, got '" + n.Scalar() + "'");
    }
  }
  int integer(const std::string& key, int fallback) {
    YAML::Node n = raw(key);
    if (!n.IsDefined() || n.IsNull()) return fallback;
    try {
      return n.as<int>();
    } catch (const YAML::Exception&) {
      fail(n, key, "expected an integer, got '" + (n.IsScalar() ? n.Scalar() : std::string("a ") + (n.IsMap() ? "map" : "list")) + "'");
    }
  }
  bool boolean(const std::string& key, bool fallback) {
    YAML::Node n = raw(key);
    if (!n.IsDefined() || n.IsNull()) return fallback;
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(n, key, "expected true or false");
    }
  }
  std::string text(const std::string& key, std::optional<std::string> fallback = {}) {
    YAML::Node n = raw(key);
    if (!n.IsDefined() || n.IsNull()) {
      if (fallback) return *fallback;
      fail(node_, key, "is required (a string)");
    }
    if (!n.IsScalar()) fail(n, key, "expected a string");
    return n.Scalar();
  }
  template <class E>
  E choice(const std::string& key, E fallback, const std::vector<std::pair<std::string, E>>& options) {
    if (!has(key)) return fallback;
    const std::string v = text(key);
    std::string names;
    for (auto& [name, value] : options) {
      if (name == v) return value;
      names += (names.empty() ? "" : ", ") + name;
    }
    fail(node_[key], key, "'" + v + "' is not one of: " + names);
  }
  // A vector of `dim` numbers, stored in the first dim components of a Vec3d.
  Vec3d vector(const std::string& key, int dim, std::optional<Vec3d> fallback = {}) {
    YAML::Node n = raw(key);
    if (!n.IsDefined() || n.IsNull()) {
      if (fallback) return *fallback;
      fail(node_, key, "is required (a list of " + std::to_string(dim) + " numbers)");
    }
    if (!n.IsSequence() || static_cast<int>(n.size()) != dim)
      fail(n, key, "expected a list of " + std::to_string(dim) + " numbers");
    Vec3d v{0, 0, 0};
    for (int k = 0; k < dim; ++k) v[k] = to_number(n[k], key);
    return v;
  }
  std::optional<Section> child(const std::string& key) {
    YAML::Node n = raw(key);
    if (!n.IsDefined() || n.IsNull()) return std::nullopt;
    if (!n.IsMap()) fail(n, key, "expected a map of keys");
    return Section(n, full(key), ctx_);
  }
  // A map of optional keys: read whether it is there or not (absent, every key takes its default),
  // so its keys are valid names for the unknown-key suggestions either way.
  Section optional_child(const std::string& key) {
    if (auto s = child(key)) return *s;
    return Section(YAML::Node(YAML::NodeType::Map), full(key), ctx_);
  }
  std::vector<Section> list(const std::string& key) {
    YAML::Node n = raw(key);
    std::vector<Section> out;
    if (!n.IsDefined() || n.IsNull()) return out;
    if (!n.IsSequence()) fail(n, key, "expected a list");
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (!n[i].IsMap()) fail(n[i], key, "each entry must be a map of keys");
      out.emplace_back(n[i], full(key) + "[" + std::to_string(i) + "]", ctx_);
    }
    return out;
  }
  // Every key of this section must have been read by now; the check itself waits for
  // reject_unknown_keys(), when every valid key of the case is known.
  void finish() const { ctx_.finished.push_back({node_, path_, known_}); }
  const YAML::Node& node() const { return node_; }
  const std::set<std::string>& known() const { return known_; }

 private:
  void remember(const std::string& key) {
    known_.insert(key);
    ctx_.valid_paths.insert(full(key));
  }

  YAML::Node node_;
  std::string path_;
  ReadContext& ctx_;
  std::set<std::string> known_;
};

// The last part of a key path: "fluid_blocks[0].min" -> "min".
std::string leaf(const std::string& path) {
  const auto dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}

// Fails on the first key (in reading order of the sections) that is given twice (YAML parsers
// silently keep one of them) or that no section asked for, suggesting the closest valid key: of the
// same section first, else of any section.
void reject_unknown_keys(ReadContext& ctx) {
  for (auto& f : ctx.finished) {
    Section section(f.node, f.path, ctx);
    std::map<std::string, int> first_line;
    for (auto it = f.node.begin(); it != f.node.end(); ++it) {
      const std::string k = it->first.Scalar();
      if (auto [at, fresh] = first_line.emplace(k, it->first.Mark().line + 1); !fresh)
        section.fail(it->first, k, at->second > 0 ? "is given twice (first on line " + std::to_string(at->second) + ")"
                                                  : "is given twice");
      if (f.known.count(k)) continue;
      std::string best;
      std::size_t best_d = 1000;
      for (auto& cand : f.known) {
        const std::size_t d = edit_distance(k, cand);
        if (d < best_d) best_d = d, best = section.full(cand);
      }
      for (auto& path : ctx.valid_paths) {
        const std::size_t d = edit_distance(k, leaf(path));
        if (d < best_d) best_d = d, best = path;
      }
      std::string msg = "unknown key";
      if (!best.empty() && best_d <= std::max<std::size_t>(2, k.size() / 3)) msg += " (did you mean '" + best + "'?)";
      section.fail(it->first, k, msg);
    }
  }
}

// Returns the key path that was set.
std::string apply_override(YAML::Node root, const std::string& file, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw CaseError(file + ": --set '" + assignment + "': expected key.path=value");
  const std::string path = assignment.substr(0, eq);
  YAML::Node value;
  try {
    const std::vector<YAML::Node> docs = YAML::LoadAll(assignment.substr(eq + 1));
    if (docs.size() > 1) throw CaseError(file + ": --set '" + assignment + "': the value holds more than one YAML document");
    if (!docs.empty()) value = docs.front();
  } catch (const YAML::Exception& e) {
    throw CaseError(file + ": --set '" + assignment + "': value is not valid YAML: " + e.msg);
  }
  std::vector<std::string> parts;
  std::stringstream ss(path);
  for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
  // yaml-cpp nodes are handles: walk down with fresh handles, never assign one node to another.
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node next = chain.back()[parts[i]];
    if (next.IsDefined() && !next.IsNull() && !next.IsMap())
      throw CaseError(file + ": --set '" + assignment + "': '" + parts[i] + "' is not a map");
    chain.push_back(next);
  }
  chain.back()[parts.back()] = value;
  return path;
}

// `wall_shear` of the tank or a solid (physics/wall_boundary.hpp), refused beside `free_slip: true`.
WallShear read_wall_shear(Section& s, bool free_slip) {
  const WallShear shear = s.choice<WallShear>("wall_shear", WallShear::Laminar, {{"laminar", WallShear::Laminar}, {"log_law", WallShear::LogLaw}});
  if (free_slip && shear == WallShear::LogLaw)
    s.fail(s.raw("wall_shear"), "wall_shear", "a free-slip surface has no shear (free_slip: true and the log law together)");
  return shear;
}

Box read_box(Section& s, int dim) {
  Box b;
  b.min = s.vector("min", dim);
  b.max = s.vector("max", dim);
  for (int k = 0; k < dim; ++k)
    if (!(b.max[k] > b.min[k])) s.fail(s.raw("max"), "max", "must be greater than min on every axis");
  return b;
}

// A list of points of `width` numbers each (polygon and polyhedron vertices).
template <std::size_t N>
std::vector<std::array<double, N>> read_points(Section& s, const std::string& key) {
  const YAML::Node n = s.raw(key);
  const std::string what = "expected a list of points, each a list of " + std::to_string(N) + " numbers";
  if (!n.IsSequence()) s.fail(n, key, what);
  std::vector<std::array<double, N>> out(n.size());
  for (std::size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsSequence() || n[i].size() != N) s.fail(n[i], key, what);
    for (std::size_t k = 0; k < N; ++k) out[i][k] = s.to_number(n[i][k], key);
  }
  return out;
}

// The keys that give a solid or a fluid block a shape (read_shape); exactly one may be given.
constexpr const char* kShapeKeys[] = {"mesh", "cylinder", "sphere", "disc", "polygon", "polyhedron"};

// The shape of a solid or a fluid block beyond a box (shape.hpp; docs/cases.md "Shapes and
// meshes"), or null when it has none: `mesh` (with scale, rotate, translate), `cylinder`,
// `sphere` (3D), `disc` (2D), `polygon` (2D), `polyhedron` (3D). A mesh path is taken relative to
// the case file's folder and stored absolute in the case the run keeps (checkpoints, restarts).
ShapePtr read_shape(Section& s, const Case& c) {
  const int d = c.dim;
  const char* given = nullptr;
  for (const char* k : kShapeKeys)
    if (s.has(k)) {
      if (given) s.fail(s.raw(k), k, std::string("give one shape: '") + given + "' or '" + k + "'");
      given = k;
    }
  for (const char* k : {"scale", "rotate", "translate"})
    if (s.has(k) && (!given || std::string(given) != "mesh")) s.fail(s.raw(k), k, "places a mesh: it needs 'mesh'");
  if (!given) return nullptr;
  const std::string key = given;
  for (const char* k : {"min", "max", "centre", "radius"})
    if (s.has(k)) s.fail(s.raw(k), k, "a shape ('" + key + "') gives the extent: no '" + k + "' beside it");
  auto want_dim = [&](int dim) {
    if (d != dim) s.fail(s.raw(key), key, "'" + key + "' is a shape of " + std::to_string(dim) + "D cases (this case is " + std::to_string(d) + "D)");
  };
  try {
    if (key == "mesh") {
      const std::string name = s.text("mesh");
      std::filesystem::path path(name);
      if (!path.is_absolute()) path = std::filesystem::path(c.file).parent_path() / path;
      path = path.lexically_normal();
      if (!path.is_absolute()) path = std::filesystem::absolute(path).lexically_normal();
      MeshPlacement at;
      if (s.has("scale")) {
        if (s.raw("scale").IsScalar()) at.scale.fill(s.number("scale"));
        else at.scale = s.vector("scale", 3);
        for (double v : at.scale)
          if (!(v != 0)) s.fail(s.raw("scale"), "scale", "must not be 0");
      }
      if (s.has("rotate")) at.rotate = s.vector("rotate", 3);
      if (s.has("translate")) at.translate = s.vector("translate", 3);
      ShapePtr shape = load_mesh(path.string(), at, d);
      YAML::Node node = s.node();  // a handle on the same YAML map
      node["mesh"] = path.string();  // the stored case names the file wherever it is read
      return shape;
    }
    if (key == "polygon") {
      want_dim(2);
      return make_polygon(read_points<2>(s, key));
    }
    if (key == "polyhedron") {
      want_dim(3);
      return make_polyhedron(read_points<3>(s, key));
    }
    auto m = s.child(key);
    if (!m) s.fail(s.raw(key), key, "expected a map of keys");
    const Vec3d centre = m->vector("centre", d);
    const double radius = m->number("radius");
    ShapePtr shape;
    if (key == "sphere") want_dim(3);
    if (key == "disc") want_dim(2);
    if (key == "cylinder" && d == 3) {
      Vec3d axis{0, 0, 1};
      const YAML::Node a = m->raw("axis");
      if (a.IsScalar()) {
        const int k = a.Scalar() == "x" ? 0 : a.Scalar() == "y" ? 1 : a.Scalar() == "z" ? 2 : -1;
        if (k < 0) m->fail(a, "axis", "expected x, y, z or a vector");
        axis = {0, 0, 0};
        axis[k] = 1;
      } else if (a.IsDefined() && !a.IsNull()) {
        axis = m->vector("axis", 3);
      }
      shape = make_cylinder(centre, axis, radius, m->number("length"));
    } else {
      shape = make_ball(centre, radius, d);  // a 2D cylinder is its disc
    }
    m->finish();
    return shape;
  } catch (const ShapeError& e) {
    s.fail(s.raw(key), key, e.what());
  }
}

// A shaped solid or block outside the tank: the message says how far, and suggests a unit
// mistake when the shape is a hundred times the tank or more.
void check_shape_in_tank(Section& s, const ShapePtr& shape, const Case& c, const Vec3d& tank_hi, const std::string& what) {
  const int d = c.dim;
  bool in = true;
  double ratio = 0.0;
  const double tol = 1e-4 * c.dp;  // a mesh stored in float32 (STL) is rounded to 1e-7 of its size
  for (int k = 0; k < d; ++k) {
    in = in && shape->lo[k] >= c.tank_origin[k] - tol && shape->hi[k] <= tank_hi[k] + tol;
    ratio = std::max(ratio, (shape->hi[k] - shape->lo[k]) / c.tank_size[k]);
  }
  if (in) return;
  const char* key = nullptr;
  for (const char* k : kShapeKeys)
    if (!key && s.has(k)) key = k;
  std::string m = fmt::format("{} lies (partly) outside the tank: its bounding box is [{:g}, {:g}, {:g}] to [{:g}, {:g}, {:g}]", what,
                              shape->lo[0], shape->lo[1], shape->lo[2], shape->hi[0], shape->hi[1], shape->hi[2]);
  if (ratio >= 100) m += fmt::format(" ({:.0f} times the tank: is the mesh in millimetres? 'scale: 0.001' converts it)", ratio);
  s.fail(s.raw(key), key, m);
}

bool inside(const Box& inner, const Vec3d& lo, const Vec3d& hi, int dim, double tol) {
  for (int k = 0; k < dim; ++k)
    if (inner.min[k] < lo[k] - tol || inner.max[k] > hi[k] + tol) return false;
  return true;
}

bool overlap(const Box& a, const Box& b, int dim, double tol) {
  for (int k = 0; k < dim; ++k)
    if (a.max[k] <= b.min[k] + tol || b.max[k] <= a.min[k] + tol) return false;
  return true;
}

// Heat transfer: a temperature [K], which cannot be below absolute zero.
double read_temperature(Section& s, const std::string& key, std::optional<double> fallback = {}) {
  const double t = s.number(key, fallback);
  if (t < 0) s.fail(s.raw(key), key, "is below absolute zero (temperatures are in kelvin)");
  return t;
}

void fill_viscosity_table(const std::vector<std::array<double, 2>>& rows, ViscosityTable& table) {
  table.points = static_cast<int>(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    table.temperature[k] = static_cast<float>(rows[k][0]);
    table.viscosity[k] = static_cast<float>(rows[k][1]);
  }
}

// A fluid's `thermal.viscosity`: [[T, mu], ...], 2 to kMaxViscosityPoints points, T ascending
// and >= 0 K, mu >= 0.
std::vector<std::array<double, 2>> read_viscosity_table(Section& t) {
  const YAML::Node n = t.raw("viscosity");
  const char* expected = "expected a table [[T, mu], ...]: temperatures [K] ascending, viscosities [Pa s]";
  if (!n.IsSequence() || n.size() < 2) t.fail(n, "viscosity", std::string(expected) + ", at least 2 rows");
  if (n.size() > static_cast<std::size_t>(kMaxViscosityPoints))
    t.fail(n, "viscosity", "at most " + std::to_string(kMaxViscosityPoints) + " rows");
  std::vector<std::array<double, 2>> table;
  for (std::size_t k = 0; k < n.size(); ++k) {
    const YAML::Node row = n[k];
    if (!row.IsSequence() || row.size() != 2) t.fail(row, "viscosity", expected);
    const double T = t.to_number(row[0], "viscosity"), mu = t.to_number(row[1], "viscosity");
    if (T < 0) t.fail(row, "viscosity", "row " + std::to_string(k) + ": the temperature is below absolute zero");
    if (mu < 0) t.fail(row, "viscosity", "row " + std::to_string(k) + ": the viscosity must be >= 0");
    if (!table.empty() && !(T > table.back()[0]))
      t.fail(row, "viscosity", "row " + std::to_string(k) + ": the temperatures must ascend");
    table.push_back({T, mu});
  }
  return table;
}

// A material's `thermal:` section (heat_transfer.hpp). Fluids: conductivity and specific_heat
// (required), expansion and reference_temperature. Walls (`wall`: the tank, a solid): conductivity
// (0: they do not conduct), with specific_heat and density when it is > 0, and a temperature; a
// solid may be `fixed` at its temperature.
ThermalSpec read_thermal(Section& t, const Case& c, bool wall, bool solid) {
  ThermalSpec s;
  s.given = true;
  s.conductivity = t.number("conductivity", wall ? std::optional<double>(0.0) : std::nullopt);
  if (s.conductivity < 0) t.fail(t.raw("conductivity"), "conductivity", "must be >= 0 [W/(m K)]");
  const bool conducts = !wall || s.conductivity > 0;
  s.specific_heat = t.number("specific_heat", conducts ? std::nullopt : std::optional<double>(0.0));
  if (conducts ? !(s.specific_heat > 0) : s.specific_heat < 0) t.fail(t.raw("specific_heat"), "specific_heat", "must be > 0 [J/(kg K)]");
  if (wall) {
    s.density = t.number("density", conducts ? std::nullopt : std::optional<double>(0.0));
    if (conducts ? !(s.density > 0) : s.density < 0) t.fail(t.raw("density"), "density", "must be > 0 [kg/m3]");
    if (t.has("temperature")) s.temperature = read_temperature(t, "temperature");
    if (solid) {
      s.fixed = t.boolean("fixed", false);
      if (s.fixed && !s.temperature) t.fail(t.raw("fixed"), "fixed", "a solid held at a fixed temperature needs thermal.temperature");
    }
  } else {
    s.expansion = t.number("expansion", 0.0);
    if (std::fabs(s.expansion) > 0.1) t.fail(t.raw("expansion"), "expansion", "must be a thermal expansion coefficient [1/K] (|beta| <= 0.1)");
    if (t.has("reference_temperature")) s.reference_temperature = read_temperature(t, "reference_temperature");
    if (t.has("viscosity")) s.viscosity = read_viscosity_table(t);
    double g2 = 0;
    for (double g : c.buoyancy_gravity) g2 += g * g;
    if (s.expansion != 0 && g2 == 0)
      t.fail(t.raw("expansion"), "expansion", "buoyancy needs gravity (the case's gravity and heat.gravity are zero)");
  }
  return s;
}

// The `thermal:` section of `parent`, if any; only with heat transfer on.
std::optional<Section> thermal_section(Section& parent, const Case& c) {
  auto t = parent.child("thermal");
  if (t && !c.heat) parent.fail(parent.raw("thermal"), "thermal", "heat transfer is off: add a `heat:` section (e.g. heat: {initial_temperature: 293.15})");
  return t;
}

// An initial temperature: a number, or {mean, amplitude, wavelength, axis} (a sinusoid).
TemperatureField read_temperature_field(Section& s, const std::string& key, int dim) {
  TemperatureField f;
  if (s.raw(key).IsScalar()) {
    f.mean = read_temperature(s, key);
    return f;
  }
  auto t = s.child(key);
  if (!t) s.fail(s.raw(key), key, "expected a temperature [K] or {mean, amplitude, wavelength, axis}");
  f.mean = read_temperature(*t, "mean");
  f.amplitude = t->number("amplitude", 0.0);
  if (!(std::fabs(f.amplitude) <= f.mean)) t->fail(t->raw("amplitude"), "amplitude", "would take the temperature below absolute zero");
  f.wavelength = t->number("wavelength", f.amplitude != 0 ? std::nullopt : std::optional<double>(1.0));
  if (!(f.wavelength > 0)) t->fail(t->raw("wavelength"), "wavelength", "must be > 0");
  const std::string axis = t->text("axis", std::string("x"));
  f.axis = axis == "x" ? 0 : axis == "y" ? 1 : axis == "z" ? 2 : -1;
  if (f.axis < 0 || f.axis >= dim) t->fail(t->raw("axis"), "axis", "'" + axis + "' is not an axis of this case");
  t->finish();
  return f;
}

// One fluid material (the `fluid:` section or an entry of `fluids:`).
void read_fluid(Section& f, FluidSpec& fluid, bool name_required, const Case& c) {
  fluid.name = name_required ? f.text("name") : f.text("name", std::string("water"));
  if (fluid.name.empty()) f.fail(f.raw("name"), "name", "must not be empty");
  fluid.density = f.number("density", 1000.0);
  if (!(fluid.density > 0)) f.fail(f.raw("density"), "density", "must be > 0");
  fluid.viscosity = f.number("viscosity", 1.0e-3);
  if (fluid.viscosity < 0) f.fail(f.raw("viscosity"), "viscosity", "must be >= 0");
  if (f.has("sound_speed") && !(f.raw("sound_speed").IsScalar() && f.raw("sound_speed").Scalar() == "auto")) {
    fluid.sound_speed = f.number("sound_speed");
    if (!(*fluid.sound_speed > 0)) f.fail(f.raw("sound_speed"), "sound_speed", "must be > 0 or 'auto'");
  }
  fluid.tait_exponent = f.number("tait_exponent", 7.0);
  if (!(fluid.tait_exponent >= 1 && fluid.tait_exponent <= 10))
    f.fail(f.raw("tait_exponent"), "tait_exponent", "must be between 1 and 10 (7 for water)");
  fluid.background_pressure = f.number("background_pressure", 0.0);
  if (fluid.background_pressure < 0) f.fail(f.raw("background_pressure"), "background_pressure", "must be >= 0");
  if (auto t = thermal_section(f, c)) {
    fluid.thermal = read_thermal(*t, c, /*wall=*/false, /*solid=*/false);
    if (!fluid.thermal.viscosity.empty()) {
      if (f.has("viscosity"))
        f.fail(f.raw("viscosity"), "viscosity", "fluid '" + fluid.name + "' has a viscosity table (thermal.viscosity): give one or the other");
      // Its constant stand-in (the log-law wall, spate info): the table at the starting temperature.
      ViscosityTable table;
      fill_viscosity_table(fluid.thermal.viscosity, table);
      fluid.viscosity = table_viscosity(table, static_cast<float>(c.initial_temperature));
    }
    t->finish();
  } else if (c.heat) {
    f.fail(f.node(), "thermal", "is required with heat transfer (conductivity [W/(m K)] and specific_heat [J/(kg K)] of fluid '" + fluid.name + "')");
  }
}

// The index of the fluid named by `key` (the first fluid when the key is absent).
int fluid_index(Section& s, const std::string& key, const Case& c) {
  if (!s.has(key)) return 0;
  const std::string name = s.text(key);
  std::string names;
  for (std::size_t k = 0; k < c.fluids.size(); ++k) {
    if (c.fluids[k].name == name) return static_cast<int>(k);
    names += (names.empty() ? "" : ", ") + c.fluids[k].name;
  }
  s.fail(s.raw(key), key, "no fluid named '" + name + "' (fluids: " + names + ")");
}

// A fluid block: a box (min, max) or a disc/sphere (centre, radius), of the fluid it names, with
// an optional sinusoidal top face (top_wave).
FluidBlock read_fluid_block(Section& f, const Case& c) {
  const int d = c.dim;
  FluidBlock b;
  if ((b.shape = read_shape(f, c))) {
    if (f.has("top_wave")) f.fail(f.raw("top_wave"), "top_wave", "a shaped block has no top wave");
    for (int k = 0; k < 3; ++k) b.min[k] = b.shape->lo[k], b.max[k] = b.shape->hi[k];
  } else if (f.has("radius") || f.has("centre")) {
    for (const char* key : {"min", "max", "top_wave"})
      if (f.has(key)) f.fail(f.raw(key), key, "a disc/sphere block has 'centre' and 'radius' only");
    b.centre = f.vector("centre", d);
    b.radius = f.number("radius");
    if (!(b.radius > 0)) f.fail(f.raw("radius"), "radius", "must be > 0");
    for (int k = 0; k < d; ++k) b.min[k] = b.centre[k] - b.radius, b.max[k] = b.centre[k] + b.radius;
  } else {
    static_cast<Box&>(b) = read_box(f, d);
    if (auto w = f.child("top_wave")) {
      b.wave_amplitude = w->number("amplitude");
      b.wavelength = w->number("wavelength");
      if (!(b.wavelength > 0)) w->fail(w->raw("wavelength"), "wavelength", "must be > 0");
      if (!(std::fabs(b.wave_amplitude) < b.max[d - 1] - b.min[d - 1]))
        w->fail(w->raw("amplitude"), "amplitude", "its magnitude must be below the block's height");
      const std::string start = w->text("start", std::string("cut"));
      if (start != "cut" && start != "displace") w->fail(w->raw("start"), "start", "must be 'cut' or 'displace'");
      b.wave_displaces = start == "displace";
      if (b.wave_displaces && !(std::fabs(b.wave_amplitude) <= 0.05 * b.wavelength))
        w->fail(w->raw("amplitude"), "amplitude", "start 'displace' is a linear mode: the amplitude must be at most 0.05 wavelengths");
      w->finish();
    }
  }
  b.fluid = fluid_index(f, "fluid", c);
  b.velocity = f.vector("velocity", d, Vec3d{0, 0, 0});
  for (int k = 0; k < d; ++k)
    if (!std::isfinite(b.velocity[k])) f.fail(f.raw("velocity"), "velocity", "must be finite [m/s]");
  b.parabolic = f.choice<bool>("velocity_profile", false, {{"uniform", false}, {"parabolic", true}});
  if (b.parabolic && !f.has("velocity")) f.fail(f.raw("velocity_profile"), "velocity_profile", "a parabolic profile needs the block's `velocity` (its peak)");
  if (f.has("temperature")) {
    if (!c.heat) f.fail(f.raw("temperature"), "temperature", "heat transfer is off: add a `heat:` section");
    b.temperature = read_temperature_field(f, "temperature", d);
  }
  return b;
}

// Why `name` cannot be a file name (case names name the default output folder out/<name>, probe
// names their probes/<name>.csv), or nothing when it can: no path separators, no '..' or hidden
// names, no control characters, not an option.
std::optional<std::string> file_name_problem(const std::string& name) {
  if (name.empty()) return "must not be empty";
  if (name.size() > 100) return "is longer than 100 characters";
  if (name.find('/') != std::string::npos || name.find('\\') != std::string::npos)
    return "must not contain '/' or '\\' (it names a file inside the output folder)";
  if (name.front() == '.') return "must not start with '.' (no '..', no hidden files)";
  if (name.front() == '-') return "must not start with '-'";
  for (const unsigned char ch : name)
    if (ch < 0x20 || ch == 0x7f) return "must not contain control characters";
  return std::nullopt;
}

// float32 positions resolve a spacing of dp only so far from the origin: beyond 2^20 dp the
// rounding of a coordinate is 1/8 dp and neighbour distances are noise (and a lattice of sites
// that large overflows its indices).
constexpr double kLargestCoordinateInDp = 1048576.0;
constexpr double kLargestCoordinate = 1.0e7;  // metres

constexpr double kDegrees = 3.14159265358979323846 / 180.0;

// The farthest corner of the box [lo, hi] from `centre`.
double reach(const Vec3& centre, const Vec3d& lo, const Vec3d& hi, int d) {
  double out = 0.0;
  for (int corner = 0; corner < (1 << d); ++corner) {
    double r2 = 0.0;
    for (int k = 0; k < d; ++k) {
      const double x = (corner >> k & 1) ? hi[k] : lo[k];
      r2 += (x - centre[k]) * (x - centre[k]);
    }
    out = std::max(out, std::sqrt(r2));
  }
  return out;
}

// A `motion:` map of the tank or of a solid (docs/cases.md, Motions). `lo`, `hi`: the moving body's
// extent (for its default centre and its reach).
MotionSpec read_motion(Section& m, const Case& c, const std::string& body, const Vec3d& lo, const Vec3d& hi) {
  const int d = c.dim;
  MotionSpec spec;
  spec.body = body;
  if (m.has("file")) {
    for (const char* key : {"period", "frequency", "translation", "rotation", "phase"})
      if (m.has(key)) m.fail(m.raw(key), key, "a time series (file) takes no '" + std::string(key) + "'");
    const std::filesystem::path given(m.text("file"));
    std::filesystem::path path = given.is_absolute() ? given : std::filesystem::path(c.file).parent_path() / given;
    // The series goes by its absolute path, in the spec and in the effective case (Case::source_yaml,
    // which checkpoints keep): relative to a checkpoint, where a restart reads that case, it is not found.
    std::error_code ec;
    if (std::filesystem::path absolute = std::filesystem::absolute(path, ec); !ec) path = std::move(absolute);
    try {
      read_motion_csv(path.lexically_normal().string(), spec);
    } catch (const std::exception& e) {
      m.fail(m.raw("file"), "file", e.what());
    }
    m.raw("file") = spec.file;
    if (d == 2)
      for (const auto& v : spec.values)
        if (v[2] != 0.0) m.fail(m.raw("file"), "file", "a 2D case has no z displacement");
  } else {
    if (m.has("period") == m.has("frequency")) m.fail(m.node(), "period", "a sinusoidal motion needs a period or a frequency (one of them)");
    if (m.has("period")) {
      const double period = m.number("period");
      if (!(period > 0)) m.fail(m.raw("period"), "period", "must be > 0");
      spec.omega = 2.0 * 3.14159265358979323846 / period;
    } else {
      const double f = m.number("frequency");
      if (!(f > 0)) m.fail(m.raw("frequency"), "frequency", "must be > 0");
      spec.omega = 2.0 * 3.14159265358979323846 * f;
    }
    const Vec3d t = m.vector("translation", d, Vec3d{0, 0, 0});
    for (int k = 0; k < 3; ++k) spec.translation[k] = t[k];
    spec.rotation = m.number("rotation", 0.0) * kDegrees;
    spec.phase = m.number("phase", 0.0) * kDegrees;
    if (t[0] == 0 && t[1] == 0 && t[2] == 0 && spec.rotation == 0)
      m.fail(m.node(), "translation", "a motion needs a translation or a rotation amplitude");
  }
  if (d == 3) {
    const Vec3d axis = m.vector("axis", 3, Vec3d{0, 0, 1});
    const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    if (!(n > 0)) m.fail(m.raw("axis"), "axis", "the rotation axis must not be zero");
    for (int k = 0; k < 3; ++k) spec.axis[k] = axis[k] / n;
  } else if (m.has("axis")) {
    m.fail(m.raw("axis"), "axis", "a 2D case rotates about z; it takes no axis");
  }
  Vec3d middle{0, 0, 0};
  for (int k = 0; k < d; ++k) middle[k] = 0.5 * (lo[k] + hi[k]);
  const Vec3d centre = m.vector("centre", d, middle);
  for (int k = 0; k < 3; ++k) spec.centre[k] = centre[k];
  spec.ramp = m.number("ramp", 0.0);
  if (spec.ramp < 0) m.fail(m.raw("ramp"), "ramp", "must be >= 0 (seconds)");
  if (m.has("end")) {
    spec.end = m.number("end");
    if (!(*spec.end > 0)) m.fail(m.raw("end"), "end", "must be > 0 (seconds)");
  }
  spec.end_ramp = m.number("end_ramp", spec.ramp);
  if (spec.end_ramp < 0 || (spec.end && spec.end_ramp > *spec.end))
    m.fail(m.raw("end_ramp"), "end_ramp", "must be >= 0 and not longer than 'end'");
  spec.reach = reach(spec.centre, lo, hi, d);
  m.finish();
  return spec;
}

// The mass, centre of mass and inertia matrix (about it) of a solid of uniform density: exact for a
// box, else by the midpoint rule over a grid of its bounding box (dp/4 in 2D, dp/2 in 3D, coarser
// beyond 4 million samples), the shape's signed distance saying what is inside.
BodySpec uniform_body(const SolidSpec& solid, double density, const Case& c) {
  const int d = c.dim;
  BodySpec b;
  const Vec3d &lo = solid.box.min, &hi = solid.box.max;
  if (!solid.shape) {
    double volume = 1.0, e[3] = {0, 0, 0};
    for (int k = 0; k < d; ++k) e[k] = hi[k] - lo[k], volume *= e[k], b.centre_of_mass[k] = 0.5 * (lo[k] + hi[k]);
    b.mass = density * volume;
    b.inertia = {b.mass * (e[1] * e[1] + e[2] * e[2]) / 12.0, b.mass * (e[0] * e[0] + e[2] * e[2]) / 12.0,
                 b.mass * (e[0] * e[0] + e[1] * e[1]) / 12.0, 0.0, 0.0, 0.0};
    return b;
  }
  double step = c.dp / (d == 2 ? 4.0 : 2.0);
  auto samples = [&](double h) {
    double n = 1.0;
    for (int k = 0; k < d; ++k) n *= std::ceil((hi[k] - lo[k]) / h);
    return n;
  };
  while (samples(step) > 4.0e6) step *= 1.25;
  int n[3] = {1, 1, 1};
  for (int k = 0; k < d; ++k) n[k] = std::max(1, static_cast<int>(std::ceil((hi[k] - lo[k]) / step)));
  double m = 0.0, first[3] = {0, 0, 0}, second[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  double cell = 1.0;
  for (int k = 0; k < d; ++k) cell *= (hi[k] - lo[k]) / n[k];
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int l = 0; l < n[2]; ++l) {
        const int ijk[3] = {i, j, l};
        double x[3] = {0, 0, 0}, normal[3];
        for (int k = 0; k < d; ++k) x[k] = lo[k] + (ijk[k] + 0.5) * (hi[k] - lo[k]) / n[k];
        if (!(solid.shape->distance(x, normal) < 0.0)) continue;
        m += 1.0;
        for (int a = 0; a < 3; ++a) {
          first[a] += x[a];
          for (int q = 0; q < 3; ++q) second[a][q] += x[a] * x[q];
        }
      }
  if (m == 0.0) return b;
  b.mass = density * m * cell;
  for (int a = 0; a < d; ++a) b.centre_of_mass[a] = first[a] / m;
  // Central second moments S_aq = sum x_a x_q / m - c_a c_q; I = (tr S) 1 - S, times the mass.
  double S[3][3];
  for (int a = 0; a < 3; ++a)
    for (int q = 0; q < 3; ++q) S[a][q] = second[a][q] / m - b.centre_of_mass[a] * b.centre_of_mass[q];
  const double trace = S[0][0] + S[1][1] + S[2][2];
  b.inertia = {b.mass * (trace - S[0][0]), b.mass * (trace - S[1][1]), b.mass * (trace - S[2][2]),
               -b.mass * S[0][1], -b.mass * S[0][2], -b.mass * S[1][2]};
  return b;
}

// A floating solid's keys (`motion: floating` on solid number `index`; docs/cases.md, "Floating
// solids"): its BodySpec (mass from `mass` or `density`, centre of mass and inertia computed unless
// given, the free degrees of freedom) and the motion slot through which the kernels see it move.
MotionSpec read_floating(Section& m, Case& c, const SolidSpec& solid, int index) {
  const int d = c.dim;
  if (!body_support())
    m.fail(m.raw("motion"), "motion", "this spate was built without Simbody (libsimbody-dev), which floating solids need");
  if (m.has("mass") == m.has("density"))
    m.fail(m.node(), "density", "a floating solid needs its density [kg/m3] or its mass [kg" + std::string(d == 2 ? " per metre" : "") + "] (one of them)");
  BodySpec b = uniform_body(solid, 1.0, c);
  if (!(b.mass > 0)) m.fail(m.node(), "motion", "solid '" + solid.name + "' holds no volume to give a mass to");
  const double density = m.has("density") ? m.number("density") : m.number("mass") / b.mass;
  if (!(density > 0)) m.fail(m.raw(m.has("density") ? "density" : "mass"), m.has("density") ? "density" : "mass", "must be > 0");
  // Mass and inertia scale with the density: the shape is integrated once (a mesh's distance
  // queries are the cost).
  b.mass *= density;
  for (double& moment : b.inertia) moment *= density;
  b.solid = index;
  b.centre_of_mass = m.vector("centre_of_mass", d, b.centre_of_mass);
  if (m.has("inertia")) {
    const YAML::Node n = m.raw("inertia");
    if (d == 2) {
      b.inertia = {0, 0, m.number("inertia"), 0, 0, 0};
      if (!(b.inertia[2] > 0)) m.fail(n, "inertia", "must be > 0 [kg m2 per metre]: the moment about z through the centre of mass");
    } else {
      if (!n.IsSequence() || (n.size() != 3 && n.size() != 6))
        m.fail(n, "inertia", "expected [Ixx, Iyy, Izz] or [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] [kg m2] about the centre of mass");
      b.inertia = {0, 0, 0, 0, 0, 0};
      for (std::size_t k = 0; k < n.size(); ++k) b.inertia[k] = m.to_number(n[k], "inertia");
      const auto& I = b.inertia;
      if (!(I[0] > 0 && I[1] > 0 && I[2] > 0) || I[0] + I[1] < I[2] || I[0] + I[2] < I[1] || I[1] + I[2] < I[0])
        m.fail(n, "inertia", "is not the inertia of a body: the moments must be > 0 and each at most the sum of the other two");
    }
  }
  if (m.has("free")) {
    const YAML::Node n = m.raw("free");
    const std::vector<std::string> names = d == 2 ? std::vector<std::string>{"x", "y", "rz"}
                                                  : std::vector<std::string>{"x", "y", "z", "rx", "ry", "rz"};
    if (!n.IsSequence() || n.size() == 0)
      m.fail(n, "free", "expected a list of the degrees of freedom left free, of: " + fmt::format("{}", fmt::join(names, ", ")));
    b.free = {false, false, false, false, false, false};
    for (std::size_t k = 0; k < n.size(); ++k) {
      const std::string name = n[k].IsScalar() ? n[k].Scalar() : "";
      const auto at = std::find(names.begin(), names.end(), name);
      if (at == names.end()) m.fail(n[k], "free", "'" + name + "' is not one of: " + fmt::format("{}", fmt::join(names, ", ")));
      const int dof = name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : name == "rx" ? 3 : name == "ry" ? 4 : 5;
      b.free[dof] = true;
    }
  }
  if (d == 2) b.free[2] = b.free[3] = b.free[4] = false;
  // Whether x lies in solid s or within dp of it.
  auto on_body = [&](const Vec3d& x, const SolidSpec& s) {
    if (s.shape) {
      double point[3] = {x[0], x[1], d == 3 ? x[2] : 0.0}, normal[3];
      return s.shape->distance(point, normal) <= c.dp;
    }
    for (int k = 0; k < d; ++k)
      if (x[k] < s.box.min[k] - c.dp || x[k] > s.box.max[k] + c.dp) return false;
    return true;
  };
  auto non_negative = [](Section& sec, const char* key) {
    const double v = sec.number(key, 0.0);
    if (v < 0) sec.fail(sec.raw(key), key, "must be >= 0");
    return v;
  };
  if (auto h = m.child("hinge")) {
    if (m.has("free")) m.fail(m.raw("free"), "free", "a hinged solid turns about its hinge only: give 'hinge' or 'free', not both");
    b.hinge.on = true;
    b.hinge.point = h->vector("point", d);
    if (!on_body(b.hinge.point, solid))
      h->fail(h->raw("point"), "point", fmt::format("the hinge lies outside solid '{}' (more than dp from it): a hinge joins the body to the ground "
                                                    "where the body is", solid.name));
    if (d == 3) {
      const Vec3d a = h->vector("axis", 3);
      const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      if (!(n > 0)) h->fail(h->raw("axis"), "axis", "the hinge's axis must not be zero");
      for (int k = 0; k < 3; ++k) b.hinge.axis[k] = a[k] / n;
    } else if (h->has("axis")) {
      h->fail(h->raw("axis"), "axis", "a 2D hinge turns about z; it takes no axis");
    }
    b.hinge.stiffness = non_negative(*h, "stiffness");
    b.hinge.damping = non_negative(*h, "damping");
    h->finish();
  }
  for (auto& sp : m.list("springs")) {
    BodySpec::Spring line;
    line.point = sp.vector("point", d);
    line.anchor = sp.vector("anchor", d);
    if (!on_body(line.point, solid))
      sp.fail(sp.raw("point"), "point", fmt::format("the spring's end lies outside solid '{}' (more than dp from it)", solid.name));
    if (sp.has("to")) {
      // Between two bodies: the other must float and come earlier in the list (its body exists).
      const std::string other = sp.text("to");
      std::optional<int> found;
      for (std::size_t k = 0; k < c.bodies.size(); ++k)
        if (c.solids[c.bodies[k].solid].name == other) found = static_cast<int>(k);
      if (!found)
        sp.fail(sp.raw("to"), "to", fmt::format("'{}' is not a floating solid listed before '{}' (write a spring between two bodies on the second)",
                                                other, solid.name));
      line.to = *found;
      if (!on_body(line.anchor, c.solids[c.bodies[*found].solid]))
        sp.fail(sp.raw("anchor"), "anchor", fmt::format("the anchor lies outside solid '{}' (more than dp from it)", other));
    } else {
      for (int k = 0; k < d; ++k)
        if (line.anchor[k] < c.tank_origin[k] - c.dp || line.anchor[k] > c.tank_origin[k] + c.tank_size[k] + c.dp)
          sp.fail(sp.raw("anchor"), "anchor", "the anchor lies outside the tank (a mooring to nowhere): tie a spring or mooring line to a point of the tank");
    }
    line.stiffness = sp.number("stiffness");
    if (!(line.stiffness > 0)) sp.fail(sp.raw("stiffness"), "stiffness", "must be > 0 [N/m" + std::string(d == 2 ? " per metre" : "") + "]");
    line.damping = non_negative(sp, "damping");
    double distance = 0.0;
    for (int k = 0; k < d; ++k) distance += (line.anchor[k] - line.point[k]) * (line.anchor[k] - line.point[k]);
    line.length = sp.number("length", std::sqrt(distance));
    if (line.length < 0) sp.fail(sp.raw("length"), "length", "must be >= 0 [m]");
    line.slack = sp.boolean("slack", false);
    sp.finish();
    b.springs.push_back(line);
  }
  b.contact.penetration = 0.01 * c.dp;
  // A hinged body is held by its hinge (often just above the floor): contact only when asked for.
  b.contact.on = !b.hinge.on;
  if (m.has("contact")) {
    const YAML::Node n = m.raw("contact");
    if (n.IsScalar()) {
      b.contact.on = m.boolean("contact", true);
    } else if (auto k = m.child("contact")) {
      b.contact.on = true;
      b.contact.penetration = k->number("penetration", b.contact.penetration);
      if (!(b.contact.penetration > 0 && b.contact.penetration <= 0.5 * c.dp))
        k->fail(k->raw("penetration"), "penetration", fmt::format("must be > 0 and at most dp/2 = {:g} m: the depth at which one contact point "
                                                                  "carries the body's weight", 0.5 * c.dp));
      for (auto [key, value] : {std::pair{"dissipation", &b.contact.dissipation}, std::pair{"friction", &b.contact.friction}}) {
        *value = k->number(key, *value);
        if (!(*value >= 0)) k->fail(k->raw(key), key, "must be >= 0");
      }
      k->finish();
    }
  }
  if (b.contact.on) {
    for (Vec3d p : solid_corners(solid, d)) {
      for (int a = 0; a < 3; ++a) p[a] -= b.centre_of_mass[a];
      b.contact.points.push_back(p);
    }
    if (d == 3)
      for (Vec3d p : sharp_edge_points(*solid_surface(solid, d), 0.5 * c.dp)) {
        for (int a = 0; a < 3; ++a) p[a] -= b.centre_of_mass[a];
        b.contact.edges.push_back(p);
      }
  }
  MotionSpec spec;
  spec.body = solid.name;
  spec.floating = static_cast<int>(c.bodies.size());
  spec.centre = b.centre_of_mass;
  spec.reach = reach(spec.centre, solid.box.min, solid.box.max, d);
  c.bodies.push_back(b);
  return spec;
}

// "x-" -> 0, "x+" -> 1, "y-" -> 2, ... (2 axis + side); -1 for anything else.
int face_index(const std::string& name, int dim) {
  if (name.size() != 2 || (name[1] != '-' && name[1] != '+')) return -1;
  const int axis = name[0] == 'x' ? 0 : name[0] == 'y' ? 1 : name[0] == 'z' ? 2 : -1;
  if (axis < 0 || axis >= dim) return -1;
  return 2 * axis + (name[1] == '+' ? 1 : 0);
}

}  // namespace

// The points of a solid that can touch a plane wall first: of its surface (the shape's, or the
// box's corners), those farthest along each of a fan of directions (2D: 64 around the circle; 3D:
// 256 spread over the sphere by the Fibonacci lattice, and the 6 axes). Every vertex of a polygon
// or polyhedron whose outward normals span more than the fan's spacing (about 6 and 13 degrees) is
// among them; a curved surface becomes that many facets. Deterministic: ties go to the first point.
ShapePtr solid_surface(const SolidSpec& solid, int dim) { return solid.shape ? solid.shape : make_box(solid.box.min, solid.box.max, dim); }

std::vector<Vec3d> solid_corners(const SolidSpec& solid, int dim) {
  std::vector<std::array<double, 3>> surface;
  if (solid.shape) {
    std::vector<std::vector<long long>> polygons;
    solid.shape->surface(surface, polygons);
  } else {
    for (int corner = 0; corner < (1 << dim); ++corner) {
      std::array<double, 3> p{0, 0, 0};
      for (int k = 0; k < dim; ++k) p[k] = (corner >> k) & 1 ? solid.box.max[k] : solid.box.min[k];
      surface.push_back(p);
    }
  }
  std::vector<std::array<double, 3>> directions;
  if (dim == 2) {
    for (int k = 0; k < 64; ++k) directions.push_back({std::cos(2 * M_PI * k / 64), std::sin(2 * M_PI * k / 64), 0.0});
  } else {
    for (int k = 0; k < 3; ++k)
      for (double sign : {-1.0, 1.0}) {
        std::array<double, 3> e{0, 0, 0};
        e[k] = sign;
        directions.push_back(e);
      }
    const int n = 256;
    for (int k = 0; k < n; ++k) {
      const double z = 1.0 - (2.0 * k + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = k * M_PI * (3.0 - std::sqrt(5.0));
      directions.push_back({r * std::cos(phi), r * std::sin(phi), z});
    }
  }
  std::vector<std::size_t> chosen;
  for (const auto& e : directions) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < surface.size(); ++i)
      if (e[0] * surface[i][0] + e[1] * surface[i][1] + e[2] * surface[i][2] > e[0] * surface[best][0] + e[1] * surface[best][1] + e[2] * surface[best][2])
        best = i;
    chosen.push_back(best);
  }
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  std::vector<std::array<double, 3>> points;
  for (std::size_t i : chosen) points.push_back(surface[i]);
  return points;
}

std::optional<std::string> tank_wall_missing(const Case& c, int face) {
  if (c.tank_shape) return "a shaped tank has no box faces (x-, x+, ...)";
  if (face < 0 || face >= 2 * c.dim) return "is not a face of this " + std::to_string(c.dim) + "D tank (x-, x+, y-, ...)";
  if (c.periodic[face / 2]) return "the tank has no wall here (the axis is periodic)";
  if (face / 2 == c.dim - 1 && face % 2 == 1 && c.open_top) return "the tank has no wall here (its top is open)";
  return std::nullopt;
}

Vec3d particle_tank_max(const Case& c) {
  Vec3d hi{0, 0, 0};
  for (int k = 0; k < c.dim; ++k) hi[k] = c.tank_origin[k] + static_cast<double>(std::lround(c.tank_size[k] / c.dp)) * c.dp;
  return hi;
}

namespace {

// A wall-pressure sensor sits on a face that fluid can touch: an interior face of the tank (not
// along a periodic axis, not the open top) or a face of a solid box. Its normal points into the
// fluid; given, it must be that face's normal; left out, the face must be unique (not an edge).
void read_wall_sensor(Section& p, const Case& c, ProbeSpec& probe) {
  const int d = c.dim;
  probe.position = p.vector("position", d);
  probe.diameter = p.number("diameter", 0.0);
  if (probe.diameter < 0) p.fail(p.raw("diameter"), "diameter", "must be >= 0 (0: a point sensor)");
  probe.window = p.number("window", 0.0);
  if (probe.window < 0) p.fail(p.raw("window"), "window", "must be >= 0 seconds (0: no averaging)");
  // Within half a particle spacing of a face: the tank's extents are rounded to whole dp, so its
  // walls may sit up to dp/2 from where the case puts them (e.g. Buchner's tank, 5.366 H long). The
  // sensor is moved onto the face the particles make.
  const double tol = 0.5 * c.dp + 1e-9;
  std::vector<std::pair<Vec3d, Vec3d>> found;  // (normal, position on the face) of every face it lies on
  auto consider = [&](const Vec3d& lo, const Vec3d& hi, int axis, double plane, double into) {
    if (std::fabs(probe.position[axis] - plane) > tol) return;
    for (int k = 0; k < d; ++k)
      if (k != axis && (probe.position[k] < lo[k] - 1e-9 || probe.position[k] > hi[k] + 1e-9)) return;
    Vec3d n{0, 0, 0}, at = probe.position;
    n[axis] = into;
    at[axis] = plane;
    found.emplace_back(n, at);
  };
  const Vec3d tank_hi = particle_tank_max(c);
  if (c.tank_shape) {  // on the container's surface: the normal into the fluid is minus the shape's
    double n[3] = {0, 0, 0};
    const double dist = c.tank_shape->distance(probe.position.data(), n);
    if (std::fabs(dist) <= tol) {
      Vec3d normal{0, 0, 0}, at = probe.position;
      for (int k = 0; k < d; ++k) normal[k] = -n[k], at[k] -= dist * n[k];
      found.emplace_back(normal, at);
    }
  }
  for (int a = 0; a < d && !c.tank_shape; ++a) {
    if (c.periodic[a]) continue;
    consider(c.tank_origin, tank_hi, a, c.tank_origin[a], 1.0);
    if (!(a == d - 1 && c.open_top)) consider(c.tank_origin, tank_hi, a, tank_hi[a], -1.0);
  }
  for (auto& s : c.solids) {
    if (s.shape) {  // on its surface: the normal is the shape's, the sensor moved onto the surface
      double n[3] = {0, 0, 0};
      const double dist = s.shape->distance(probe.position.data(), n);
      if (std::fabs(dist) > tol) continue;
      Vec3d normal{0, 0, 0}, at = probe.position;
      for (int k = 0; k < d; ++k) normal[k] = n[k], at[k] -= dist * n[k];
      found.emplace_back(normal, at);
      continue;
    }
    for (int a = 0; a < d; ++a) {
      consider(s.box.min, s.box.max, a, s.box.min[a], -1.0);
      consider(s.box.min, s.box.max, a, s.box.max[a], 1.0);
    }
  }
  if (found.empty())
    p.fail(p.raw("position"), "position",
           "a wall_pressure sensor must lie on a face of the tank interior or of a solid (within dp/2)");
  if (!p.has("normal")) {
    if (found.size() > 1) p.fail(p.raw("position"), "position", "lies on an edge of two faces: give 'normal' to choose one");
    std::tie(probe.normal, probe.position) = found[0];
    return;
  }
  Vec3d n = p.vector("normal", d);
  double length = 0;
  for (int k = 0; k < d; ++k) length += n[k] * n[k];
  length = std::sqrt(length);
  if (!(length > 0)) p.fail(p.raw("normal"), "normal", "must be a non-zero vector");
  for (int k = 0; k < d; ++k) n[k] /= length;
  for (auto& [m, at] : found) {
    double dot = 0;
    for (int k = 0; k < d; ++k) dot += m[k] * n[k];
    if (dot > 1 - 1e-6) {
      probe.normal = m;
      probe.position = at;
      return;
    }
  }
  p.fail(p.raw("normal"), "normal", "is not the normal (pointing into the fluid) of the face the sensor lies on");
}

// Whether a point on a face (read_wall_sensor put it exactly there) lies on the surface of a body
// that moves: the tank's walls, or a solid box, with a motion.
bool on_moving_body(const Vec3d& x, const Case& c) {
  const int d = c.dim;
  const double tol = 1e-9;
  auto on_box = [&](const Vec3d& lo, const Vec3d& hi) {
    bool inside = true, on_face = false;
    for (int k = 0; k < d; ++k) {
      inside = inside && x[k] >= lo[k] - tol && x[k] <= hi[k] + tol;
      on_face = on_face || std::fabs(x[k] - lo[k]) <= tol || std::fabs(x[k] - hi[k]) <= tol;
    }
    return inside && on_face;
  };
  for (const SolidSpec& s : c.solids) {
    if (s.motion < 0) continue;
    double n[3];
    if (s.shape ? std::fabs(s.shape->distance(x.data(), n)) <= 1e-6 : on_box(s.box.min, s.box.max)) return true;
  }
  if (c.tank_motion < 0) return false;
  double n[3];
  if (c.tank_shape) return std::fabs(c.tank_shape->distance(x.data(), n)) <= 1e-6;
  return on_box(c.tank_origin, particle_tank_max(c));
}

// `tank.thermal.faces`: {x-: {temperature: T}, x+: {heat_flux: q}, y-: adiabatic, ...}, on faces the
// tank has (not along a periodic axis, not the open top).
void read_tank_faces(Section& t, Case& c) {
  auto faces = t.child("faces");
  if (!faces) return;
  const int d = c.dim;
  for (auto it = faces->node().begin(); it != faces->node().end(); ++it) {
    const std::string name = it->first.Scalar();
    const int f = face_index(name, d);
    if (auto why = tank_wall_missing(c, f)) faces->fail(it->first, name, *why);
    FaceThermalSpec& spec = c.tank_faces[f];
    if (faces->raw(name).IsScalar()) {
      const std::string v = faces->text(name);
      if (v == "adiabatic") spec.kind = ThermalCondition::Adiabatic;
      else if (v == "conducting" && c.tank_thermal.conductivity > 0) spec.kind = ThermalCondition::Conducting;
      else faces->fail(faces->raw(name), name, v == "conducting" ? "a conducting face needs tank.thermal.conductivity > 0"
                                                                  : "expected adiabatic, conducting, {temperature: T} or {heat_flux: q}");
      continue;
    }
    auto e = faces->child(name);
    if (!e || e->has("temperature") == e->has("heat_flux"))
      faces->fail(faces->raw(name), name, "expected adiabatic, conducting, {temperature: T} or {heat_flux: q}");
    if (e->has("temperature")) {
      spec.kind = ThermalCondition::FaceTemperature;
      spec.value = read_temperature(*e, "temperature");
    } else {
      spec.kind = ThermalCondition::FaceFlux;
      spec.value = e->number("heat_flux");
    }
    e->finish();
  }
  faces->finish();
}

Case read(Section& root, const std::string& file) {
  Case c;
  c.file = file;
  c.name = root.text("name");
  if (auto why = file_name_problem(c.name)) root.fail(root.raw("name"), "name", "'" + c.name + "' " + *why);
  c.dim = root.integer("dimensions", 3);
  if (c.dim != 2 && c.dim != 3) root.fail(root.raw("dimensions"), "dimensions", "must be 2 or 3");
  const int d = c.dim;
  c.dp = root.number("dp");
  if (!(c.dp > 0)) root.fail(root.raw("dp"), "dp", "particle spacing must be > 0");
  c.smoothing_ratio = root.number("smoothing_ratio", 1.3);
  if (c.smoothing_ratio < 1.0 || c.smoothing_ratio > 3.0)
    root.fail(root.raw("smoothing_ratio"), "smoothing_ratio", "must be between 1 and 3 (h = ratio x dp)");
  c.kernel = root.choice<KernelType>("kernel", KernelType::WendlandC2,
                                     {{"wendland_c2", KernelType::WendlandC2}, {"cubic_spline", KernelType::CubicSpline}});
  Vec3d g_default{0, 0, 0};
  g_default[d - 1] = -9.81;
  c.gravity = root.vector("gravity", d, g_default);
  // Heat transfer: on with a `heat:` section (heat_transfer.hpp).
  if (auto h = root.child("heat")) {
    c.heat = true;
    c.initial_temperature = read_temperature(*h, "initial_temperature", 293.15);
    c.buoyancy_gravity = h->vector("gravity", d, c.gravity);
    h->finish();
  } else if (root.has("heat")) {
    root.fail(root.raw("heat"), "heat", "expected a map (e.g. {initial_temperature: 293.15})");
  }

  // Fluids: `fluid:` (one), or a `fluids:` list of materials (several phases); `fluid:` then keeps
  // only the case-wide artificial_viscosity, body_force and tension.
  const bool listed = root.has("fluids");
  if (listed) {
    auto entries = root.list("fluids");
    if (entries.empty()) root.fail(root.raw("fluids"), "fluids", "expected a list of at least one fluid");
    if (entries.size() > static_cast<std::size_t>(kMaxFluids))
      root.fail(root.raw("fluids"), "fluids", "at most " + std::to_string(kMaxFluids) + " fluids");
    c.fluids.clear();
    for (auto& e : entries) {
      FluidSpec fluid;
      read_fluid(e, fluid, /*name_required=*/true, c);
      for (auto& other : c.fluids)
        if (other.name == fluid.name) e.fail(e.raw("name"), "name", "fluid '" + fluid.name + "' is defined twice");
      e.finish();
      c.fluids.push_back(fluid);
    }
  }
  {
    auto f = root.optional_child("fluid");
    if (!listed) {
      read_fluid(f, c.fluids[0], /*name_required=*/false, c);
    } else {
      for (const char* key : {"name", "density", "viscosity", "sound_speed", "tait_exponent", "background_pressure", "thermal"})
        if (f.has(key))
          f.fail(f.raw(key), key, "with a 'fluids' list each fluid's properties go in its entry; 'fluid' keeps only "
                                  "artificial_viscosity, wall_artificial_viscosity, body_force, tension, wall_tension and portable_eos");
    }
    c.artificial_viscosity = f.number("artificial_viscosity", 0.0);
    if (c.artificial_viscosity < 0) f.fail(f.raw("artificial_viscosity"), "artificial_viscosity", "must be >= 0");
    c.wall_artificial_viscosity = f.number("wall_artificial_viscosity", 1.0);
    if (!(c.wall_artificial_viscosity >= 0 && c.wall_artificial_viscosity <= 1))
      f.fail(f.raw("wall_artificial_viscosity"), "wall_artificial_viscosity", "must be between 0 and 1");
    c.body_force = f.vector("body_force", d, Vec3d{0, 0, 0});
    c.tension = f.boolean("tension", true);
    c.wall_tension = f.boolean("wall_tension", false);
    if (c.wall_tension && !c.tension)
      f.fail(f.raw("wall_tension"), "wall_tension", "walls that hold tension need a fluid that takes it (tension: false clips the fluid's pressure at 0)");
    c.portable_eos = f.boolean("portable_eos", false);
    f.finish();
  }
  // Surface tension: `surface_tension: [{between: [a, b], coefficient: sigma}, ...]`.
  for (auto& e : root.list("surface_tension")) {
    const YAML::Node between = e.raw("between");
    if (!between.IsDefined() || !between.IsSequence() || between.size() != 2 || !between[0].IsScalar() || !between[1].IsScalar())
      e.fail(between.IsDefined() ? between : e.node(), "between", "expected the names of two fluids, e.g. [water, air]");
    SurfaceTensionSpec st;
    int index[2] = {-1, -1};
    for (int k = 0; k < 2; ++k) {
      const std::string name = between[k].Scalar();
      for (std::size_t f = 0; f < c.fluids.size(); ++f)
        if (c.fluids[f].name == name) index[k] = static_cast<int>(f);
      if (index[k] < 0) {
        std::string names;
        for (auto& f : c.fluids) names += (names.empty() ? "" : ", ") + f.name;
        e.fail(between[k], "between", "no fluid named '" + name + "' (fluids: " + names + ")");
      }
    }
    if (index[0] == index[1]) e.fail(between, "between", "names the same fluid twice (surface tension acts between two fluids)");
    st.a = index[0], st.b = index[1];
    for (auto& other : c.surface_tension)
      if ((other.a == st.a && other.b == st.b) || (other.a == st.b && other.b == st.a))
        e.fail(between, "between", "this pair of fluids already has a coefficient");
    st.coefficient = e.number("coefficient");
    if (!(st.coefficient >= 0)) e.fail(e.raw("coefficient"), "coefficient", "must be >= 0 [N/m]");
    e.finish();
    c.surface_tension.push_back(st);
  }
  {
    auto s = root.optional_child("density");
    c.density_mode = s.choice<DensityMode>("mode", DensityMode::Continuity,
                                            {{"continuity", DensityMode::Continuity}, {"summation", DensityMode::Summation}});
    c.diffusion = s.choice<DensityDiffusion>(
        "diffusion", DensityDiffusion::Fourtakas,
        {{"fourtakas", DensityDiffusion::Fourtakas}, {"molteni_colagrossi", DensityDiffusion::MolteniColagrossi},
         {"riemann", DensityDiffusion::Riemann}, {"antuono", DensityDiffusion::Antuono}, {"none", DensityDiffusion::None}});
    c.delta = s.number("delta", 0.1);
    if (c.delta < 0 || c.delta > 1) s.fail(s.raw("delta"), "delta", "must be between 0 and 1");
    c.density_min_ratio = s.number("min_ratio", 0.5);
    c.density_max_ratio = s.number("max_ratio", 2.0);
    // Outside these limits the run stops as unstable; limits that exclude rho0 would stop it at once.
    if (!(c.density_min_ratio >= 0 && c.density_min_ratio < 1))
      s.fail(s.raw("min_ratio"), "min_ratio", "must be in [0, 1) (a fraction of the reference density)");
    if (!(c.density_max_ratio > 1)) s.fail(s.raw("max_ratio"), "max_ratio", "must be > 1 (a multiple of the reference density)");
    c.closed_volume = s.boolean("closed_volume", false);
    if (c.closed_volume && c.density_mode != DensityMode::Continuity)
      s.fail(s.raw("closed_volume"), "closed_volume", "is for the continuity density (mode: continuity); a summation density follows the particles and does not drift");
    s.finish();
  }
  {
    auto m = root.optional_child("momentum");
    c.flux = m.choice<MomentumFlux>("flux", MomentumFlux::Central, {{"central", MomentumFlux::Central}, {"riemann", MomentumFlux::Riemann}});
    c.riemann_limiter = m.number("riemann_limiter", 3.0);
    if (!(c.riemann_limiter >= 0)) m.fail(m.raw("riemann_limiter"), "riemann_limiter", "must be >= 0");
    c.pressure_difference = m.choice<bool>("pressure_gradient", false, {{"symmetric", false}, {"difference", true}});
    if (c.pressure_difference && c.fluids.size() < 2)
      m.fail(m.raw("pressure_gradient"), "pressure_gradient", "'difference' is for several fluids (their interfaces); one fluid keeps 'symmetric'");
    m.finish();
  }
  {
    auto r = root.optional_child("relax");
    c.relax_steps = r.integer("steps", 0);
    if (!(c.relax_steps >= 0 && c.relax_steps <= 100000)) r.fail(r.raw("steps"), "steps", "must be between 0 and 100000 (0: no relaxation)");
    c.relax_perturbation = r.number("perturbation", 0.2);
    if (!(c.relax_perturbation >= 0 && c.relax_perturbation <= 0.5))
      r.fail(r.raw("perturbation"), "perturbation", "must be between 0 and 0.5 (a fraction of dp)");
    c.relax_rate = r.number("rate", 0.1);
    if (!(c.relax_rate > 0 && c.relax_rate <= 1)) r.fail(r.raw("rate"), "rate", "must be in (0, 1]");
    r.finish();
  }
  {
    auto t = root.optional_child("turbulence");
    c.sps = t.choice<bool>("model", false, {{"none", false}, {"sps", true}});
    c.smagorinsky = t.number("smagorinsky", 0.12);
    if (!(c.smagorinsky > 0 && c.smagorinsky <= 1)) t.fail(t.raw("smagorinsky"), "smagorinsky", "must be in (0, 1]");
    c.sps_isotropic = t.number("isotropic", 0.0066);
    if (!(c.sps_isotropic >= 0 && c.sps_isotropic <= 1)) t.fail(t.raw("isotropic"), "isotropic", "must be in [0, 1]");
    t.finish();
  }
  {
    auto s = root.optional_child("shifting");
    c.shifting = s.boolean("enabled", false);
    c.shifting_coefficient = s.number("coefficient", 1.0);
    if (!(c.shifting_coefficient >= 0 && c.shifting_coefficient <= 10))
      s.fail(s.raw("coefficient"), "coefficient", "must be between 0 and 10");
    c.shifting_mach = s.number("mach", 0.1);
    if (!(c.shifting_mach > 0 && c.shifting_mach <= 1)) s.fail(s.raw("mach"), "mach", "must be in (0, 1]");
    c.shifting_volume_consistent = s.boolean("volume_consistent", false);
    c.shifting_free_surface = s.boolean("free_surface", true);
    c.shifting_correct_velocity = s.boolean("correct_velocity", false);
    s.finish();
  }
  if (auto t = root.child("time")) {
    c.end_time = t->number("end");
    if (!(c.end_time > 0)) t->fail(t->raw("end"), "end", "must be > 0");
    if (t->has("dt") && !(t->raw("dt").IsScalar() && t->raw("dt").Scalar() == "auto")) {
      c.fixed_dt = t->number("dt");
      if (!(*c.fixed_dt > 0)) t->fail(t->raw("dt"), "dt", "must be > 0 or 'auto'");
      // A step that needs more than 1e12 steps to the end would run for ever (and below the
      // resolution of t not even advance it).
      if (c.end_time / *c.fixed_dt > 1e12) {
        std::ostringstream m;
        m << "a fixed step of " << *c.fixed_dt << " s takes more than 1e12 steps to time.end = " << c.end_time << " s";
        t->fail(t->raw("dt"), "dt", m.str());
      }
    }
    c.cfl = t->number("cfl", 0.2);
    if (!(c.cfl > 0 && c.cfl <= 1)) t->fail(t->raw("cfl"), "cfl", "must be in (0, 1]");
    t->finish();
  } else {
    root.fail(root.node(), "time", "is required (a map with at least 'end')");
  }

  auto tank = root.child("tank");
  if (!tank) root.fail(root.node(), "tank", "is required");
  // A container of any shape (a mesh, a cylinder, ...): its inside is the tank's interior, its
  // bounding box the lattice's box (from the box's lower corner, whole dp), its surface closed.
  c.tank_shape = read_shape(*tank, c);
  if (c.tank_shape) {
    for (const char* k : {"origin", "size"})
      if (tank->has(k)) tank->fail(tank->raw(k), k, "a shaped tank's extent is its shape's: no '" + std::string(k) + "' beside it");
    for (int k = 0; k < d; ++k) {
      c.tank_origin[k] = c.tank_shape->lo[k];
      // A mesh stored in float32 (STL) is rounded to 1e-7 of its size: a face on a whole dp stays there.
      c.tank_size[k] = std::max(1.0, std::ceil((c.tank_shape->hi[k] - c.tank_shape->lo[k]) / c.dp - 1e-4)) * c.dp;
    }
  } else {
    c.tank_origin = tank->vector("origin", d, Vec3d{0, 0, 0});
    c.tank_size = tank->vector("size", d);
  }
  for (int k = 0; k < d; ++k)
    if (!(c.tank_size[k] > 0)) tank->fail(tank->raw("size"), "size", "every extent must be > 0");
  c.wall_layers = tank->integer("wall_layers", 3);
  if (c.wall_layers < 1 || c.wall_layers > 8) tank->fail(tank->raw("wall_layers"), "wall_layers", "must be between 1 and 8");
  c.tank_surface_particles = tank->choice<bool>("wall_particles", false, {{"lattice", false}, {"surface", true}});
  if (c.tank_surface_particles && !c.tank_shape)
    tank->fail(tank->raw("wall_particles"), "wall_particles",
               "a box tank's wall particles already lie in layers along its faces; 'surface' is for a shaped tank (mesh, disc, ...)");
  c.open_top = tank->boolean("open_top", !c.tank_shape);
  if (c.tank_shape && c.open_top)
    tank->fail(tank->raw("open_top"), "open_top", "a shaped tank is a closed surface (make it taller than the water for an open vessel)");
  c.headroom = tank->number("headroom", 0.5);
  if (c.headroom < 0 || c.headroom > 10) tank->fail(tank->raw("headroom"), "headroom", "must be >= 0 and <= 10 (a fraction of the tank height)");
  c.max_removed_fraction = tank->number("max_removed_fraction", 0.05);
  if (!(c.max_removed_fraction >= 0 && c.max_removed_fraction <= 1))
    tank->fail(tank->raw("max_removed_fraction"), "max_removed_fraction", "must be in [0, 1] (a fraction of the fluid particles)");
  // `periodic` and `free_slip`: lists of axes, e.g. [x]; `free_slip: true` for every face (of a box
  // tank: every axis not periodic; of a shaped tank: its whole surface).
  auto axes = [&](const std::string& key, std::array<bool, 3>& out) {
    if (!tank->has(key)) return;
    YAML::Node p = tank->raw(key);
    if (key == "free_slip" && p.IsScalar()) {
      const bool all = tank->boolean(key, false);
      if (c.tank_shape) c.shaped_tank_free_slip = all;
      else
        for (int k = 0; k < d; ++k) out[k] = all && !c.periodic[k];
      return;
    }
    if (!p.IsSequence()) tank->fail(p, key, key == "free_slip" ? "expected a list of axes, e.g. [x], or true for every face" : "expected a list of axes, e.g. [x]");
    for (auto a : p) {
      const std::string axis = a.IsScalar() ? a.Scalar() : "";
      const int k = axis == "x" ? 0 : axis == "y" ? 1 : axis == "z" ? 2 : -1;
      if (k < 0 || k >= d) tank->fail(a, key, "'" + axis + "' is not an axis of this " + std::to_string(d) + "D case");
      if (key == "periodic" && k == d - 1) tank->fail(a, key, "the vertical axis cannot be periodic");
      out[k] = true;
    }
  };
  axes("periodic", c.periodic);
  axes("free_slip", c.free_slip);
  for (int k = 0; k < d; ++k)
    if (c.periodic[k] && c.free_slip[k]) tank->fail(tank->raw("free_slip"), "free_slip", "an axis cannot be periodic and have walls");
  c.wall_shear = read_wall_shear(*tank, c.shaped_tank_free_slip);
  if (c.tank_shape) {  // axes are a box tank's, face by face
    if (tank->has("periodic")) tank->fail(tank->raw("periodic"), "periodic", "is for a box tank's faces, not a shaped tank");
    if (tank->has("free_slip") && !tank->raw("free_slip").IsScalar())
      tank->fail(tank->raw("free_slip"), "free_slip", "a list of axes is for a box tank's faces; a shaped tank's surface takes true or false");
  }
  if (auto t = thermal_section(*tank, c)) {
    c.tank_thermal = read_thermal(*t, c, /*wall=*/true, /*solid=*/false);
    read_tank_faces(*t, c);
    t->finish();
  }
  if (auto m = tank->child("motion")) {
    Vec3d lo = c.tank_origin, hi = c.tank_origin;
    for (int k = 0; k < d; ++k) {
      lo[k] -= c.wall_layers * c.dp;
      hi[k] += c.tank_size[k] + c.wall_layers * c.dp;
    }
    c.tank_motion = static_cast<int>(c.motions.size());
    c.motions.push_back(read_motion(*m, c, "tank", lo, hi));
    for (int k = 0; k < d; ++k)
      if (c.free_slip[k])
        tank->fail(tank->raw("free_slip"), "free_slip", "a box tank's free-slip faces are for a tank at rest (not with tank.motion)");
    if (c.wall_shear == WallShear::LogLaw && !c.tank_shape)
      tank->fail(tank->raw("wall_shear"), "wall_shear",
                 "the log law on a moving tank needs each wall particle's frame: a shaped tank's (mesh, polyhedron, ...), not a box tank's faces");
  }
  if (c.tank_motion >= 0)
    for (const FaceThermalSpec& f : c.tank_faces)
      if (f.kind != ThermalCondition::Conducting)
        tank->fail(tank->raw("thermal"), "thermal.faces", "face conditions are for a tank at rest (not with tank.motion)");
  tank->finish();
  if (auto dr = root.child("drive")) {
    // A periodic flow driven at a given mean velocity: only along periodic axes (across a wall
    // the mean velocity is zero by itself).
    c.drive.on = true;
    c.drive.mean_velocity = dr->vector("mean_velocity", d);
    bool any = false;
    for (int k = 0; k < d; ++k) any = any || c.periodic[k];
    if (!any) root.fail(root.raw("drive"), "drive", "needs a periodic axis (tank.periodic) to drive the flow along");
    for (int k = 0; k < d; ++k) {
      c.drive.axes[k] = c.periodic[k];
      if (!c.periodic[k] && c.drive.mean_velocity[k] != 0)
        dr->fail(dr->raw("mean_velocity"), "mean_velocity",
                 std::string("the ") + "xyz"[k] + " component must be 0: only a periodic axis can be driven (tank.periodic)");
      if (!std::isfinite(c.drive.mean_velocity[k])) dr->fail(dr->raw("mean_velocity"), "mean_velocity", "must be finite [m/s]");
    }
    c.drive.response_time = dr->number("response_time", 0.0);
    if (!(c.drive.response_time >= 0) || !std::isfinite(c.drive.response_time))
      dr->fail(dr->raw("response_time"), "response_time", "must be >= 0 [s] (0: one time step)");
    dr->finish();
  }
  if (auto z = root.child("relaxation_zone")) {
    c.zone.min = z->vector("min", d);
    c.zone.max = z->vector("max", d);
    for (int k = 0; k < d; ++k) {
      if (!(c.zone.max[k] > c.zone.min[k])) z->fail(z->raw("max"), "max", "must be greater than min on every axis");
      if (c.zone.min[k] < c.tank_origin[k] - 1e-9 || c.zone.max[k] > c.tank_origin[k] + c.tank_size[k] + 1e-9)
        z->fail(z->raw("max"), "min/max", "the zone must lie inside the tank");
    }
    c.zone.velocity = z->vector("velocity", d);
    for (int k = 0; k < d; ++k)
      if (!std::isfinite(c.zone.velocity[k])) z->fail(z->raw("velocity"), "velocity", "must be finite [m/s]");
    c.zone.parabolic = z->choice<bool>("velocity_profile", false, {{"uniform", false}, {"parabolic", true}});
    c.zone.time = z->number("time");
    if (!(c.zone.time > 0) || !std::isfinite(c.zone.time))
      z->fail(z->raw("time"), "time", "must be > 0 [s] (the relaxation's time constant; several time steps)");
    z->finish();
  }
  {
    double largest = 0;
    for (int k = 0; k < d; ++k) {
      const double extra = c.wall_layers * c.dp + (k == d - 1 ? c.headroom * c.tank_size[k] : 0.0);
      largest = std::max({largest, std::fabs(c.tank_origin[k] - extra), std::fabs(c.tank_origin[k] + c.tank_size[k] + extra)});
    }
    if (largest > kLargestCoordinate) {
      bool far_origin = false;
      for (int k = 0; k < d; ++k) far_origin = far_origin || std::fabs(c.tank_origin[k]) > kLargestCoordinate / 2;
      std::ostringstream m;
      m << "the domain reaches " << largest << " m from the origin of the coordinates; at most 1e7 m";
      const char* key = far_origin ? "origin" : "size";
      tank->fail(tank->raw(key), key, m.str());
    }
    if (largest / c.dp > kLargestCoordinateInDp) {
      std::ostringstream m;
      m << "dp = " << c.dp << " m is too fine for float32 positions in a domain reaching " << largest
        << " m from the origin (at most 2^20 spacings: dp >= " << largest / kLargestCoordinateInDp << " m)";
      root.fail(root.raw("dp"), "dp", m.str());
    }
  }

  const Vec3d tank_hi{c.tank_origin[0] + c.tank_size[0], c.tank_origin[1] + c.tank_size[1], c.tank_origin[2] + c.tank_size[2]};
  const double tol = 1e-9;
  for (auto& f : root.list("fluid_blocks")) {
    const FluidBlock b = read_fluid_block(f, c);
    f.finish();
    // A shaped tank cuts every block to its inside (a box filling a vessel to a level).
    if (b.shape && !c.tank_shape) check_shape_in_tank(f, b.shape, c, tank_hi, "the fluid block");
    if (!b.shape && !c.tank_shape && !inside(b, c.tank_origin, tank_hi, d, tol))
      f.fail(f.node(), b.radius > 0 ? "radius" : "max", "fluid block lies (partly) outside the tank");
    c.fluid_blocks.push_back(b);
  }
  // wet_bed: a depth (of the first fluid), or {depth, fluid}.
  if (root.has("wet_bed") && root.raw("wet_bed").IsMap()) {
    auto bed = *root.child("wet_bed");
    c.wet_bed = bed.number("depth");
    c.wet_bed_fluid = fluid_index(bed, "fluid", c);
    if (c.wet_bed < 0 || c.wet_bed >= c.tank_size[d - 1]) bed.fail(bed.raw("depth"), "depth", "must be >= 0 and below the tank top");
    bed.finish();
  } else {
    c.wet_bed = root.number("wet_bed", 0.0);
    if (c.wet_bed < 0 || c.wet_bed >= c.tank_size[d - 1]) root.fail(root.raw("wet_bed"), "wet_bed", "depth must be >= 0 and below the tank top");
  }
  std::set<std::string> solid_names;
  for (auto& s : root.list("solids")) {
    SolidSpec spec;
    spec.name = s.text("name");
    spec.shape = read_shape(s, c);
    if (spec.shape) {
      check_shape_in_tank(s, spec.shape, c, tank_hi, "solid '" + spec.name + "'");
      for (int k = 0; k < 3; ++k) spec.box.min[k] = spec.shape->lo[k], spec.box.max[k] = spec.shape->hi[k];
    } else {
      spec.box = read_box(s, d);
    }
    spec.hollow = s.boolean("hollow", true);
    spec.free_slip = s.boolean("free_slip", false);
    spec.surface_particles = s.choice<bool>("wall_particles", false, {{"lattice", false}, {"surface", true}});
    if (spec.surface_particles && !spec.hollow)
      s.fail(s.raw("wall_particles"), "wall_particles", "surface layers shell the solid; a filled solid (hollow: false) stays on the lattice");
    spec.wall_shear = read_wall_shear(s, spec.free_slip);
    if (auto t = thermal_section(s, c)) {
      spec.thermal = read_thermal(*t, c, /*wall=*/true, /*solid=*/true);
      t->finish();
    }
    if (s.has("motion") && s.raw("motion").IsScalar()) {
      // `motion: floating`: the water moves it (its mass and the rest are keys of the solid).
      if (s.raw("motion").Scalar() != "floating")
        s.fail(s.raw("motion"), "motion", "'" + s.raw("motion").Scalar() + "' is not a motion: 'floating', or a map of a prescribed motion's keys");
      spec.motion = static_cast<int>(c.motions.size());
      c.motions.push_back(read_floating(s, c, spec, static_cast<int>(c.solids.size())));
    } else if (auto m = s.child("motion")) {
      spec.motion = static_cast<int>(c.motions.size());
      c.motions.push_back(read_motion(*m, c, spec.name, spec.box.min, spec.box.max));
    }
    if (spec.motion < 0 || c.motions[spec.motion].floating < 0)
      for (const char* key : {"density", "mass", "centre_of_mass", "inertia", "free", "hinge", "springs", "contact"})
        if (s.has(key)) s.fail(s.raw(key), key, "only a floating solid (motion: floating) takes '" + std::string(key) + "'");
    s.finish();
    if (!solid_names.insert(spec.name).second) s.fail(s.raw("name"), "name", "solid '" + spec.name + "' is defined twice");
    if (!spec.shape && !inside(spec.box, c.tank_origin, tank_hi, d, tol)) s.fail(s.node(), "max", "solid lies (partly) outside the tank");
    // A shaped solid or block: the fluid is the block less the solid (the generator leaves dp/2 clear).
    for (auto& b : c.fluid_blocks)
      if (!spec.shape && !b.shape && overlap(b, spec.box, d, tol))
        s.fail(s.node(), "min", "solid '" + spec.name + "' overlaps a fluid block");
    c.solids.push_back(spec);
  }
  if (c.solids.size() > 200) root.fail(root.raw("solids"), "solids", "at most 200 solids");
  if (c.fluid_blocks.size() > 200) root.fail(root.raw("fluid_blocks"), "fluid_blocks", "at most 200 fluid blocks");
  if (static_cast<int>(c.motions.size()) > kMaxMotions)
    root.fail(root.raw("solids"), "solids", "at most " + std::to_string(kMaxMotions) + " motions (tank and solids together)");
  if (!c.motions.empty() && (c.periodic[0] || c.periodic[1] || c.periodic[2]))
    tank->fail(tank->raw("periodic"), "periodic", "moving walls need a closed tank: no periodic axes with a motion");
  // The Riemann flux's wall term (finish_fluid_rates) takes the wall at rest (the mirror velocity
  // -v_i); with a moving wall it would damp the fluid that follows the wall.
  if (!c.motions.empty() && c.flux == MomentumFlux::Riemann)
    root.fail(root.raw("momentum"), "momentum.flux", "'riemann' assumes static walls; it cannot be combined with a motion (use 'central')");
  if (c.fluid_blocks.empty() && c.wet_bed <= 0) root.fail(root.node(), "fluid_blocks", "the case has no fluid (no fluid_blocks and no wet_bed)");

  auto shaped_solid = [&](const std::string& name) {
    for (const SolidSpec& s : c.solids)
      if (s.name == name) return s.shape != nullptr;
    return false;
  };
  for (auto& p : root.list("probes")) {
    ProbeSpec probe;
    probe.name = p.text("name");
    if (auto why = file_name_problem(probe.name)) p.fail(p.raw("name"), "name", "'" + probe.name + "' " + *why);
    // Each probe writes probes/<name>.csv.
    for (auto& other : c.probes)
      if (other.name == probe.name) p.fail(p.raw("name"), "name", "probe '" + probe.name + "' is defined twice");
    probe.type = p.choice<ProbeType>("type", ProbeType::Pressure,
                                     {{"pressure", ProbeType::Pressure}, {"velocity", ProbeType::Velocity}, {"height", ProbeType::Height},
                                      {"force", ProbeType::Force}, {"front", ProbeType::Front}, {"wall_pressure", ProbeType::WallPressure},
                                      {"centroid", ProbeType::Centroid}, {"temperature", ProbeType::Temperature},
                                      {"heat_flux", ProbeType::HeatFlux}, {"interface", ProbeType::Interface},
                                      {"body", ProbeType::Body}, {"drive", ProbeType::Drive}});
    if (probe.type == ProbeType::Drive && !c.drive.on)
      p.fail(p.raw("type"), "type", "a drive probe records the body force of a `drive:` section, and the case has none");
    if ((probe.type == ProbeType::Temperature || probe.type == ProbeType::HeatFlux) && !c.heat)
      p.fail(p.raw("type"), "type", "a " + p.text("type") + " probe needs heat transfer (a `heat:` section)");
    // A phase (fluid) to measure: required by a centroid, optional for a point, a gauge or a front.
    const bool phased = probe.type == ProbeType::Pressure || probe.type == ProbeType::Velocity || probe.type == ProbeType::Temperature ||
                        probe.type == ProbeType::Height || probe.type == ProbeType::Centroid || probe.type == ProbeType::Front ||
                        probe.type == ProbeType::Interface;
    const bool needs_phase = probe.type == ProbeType::Centroid || probe.type == ProbeType::Interface;
    if (needs_phase && !p.has("phase")) p.text("phase");  // reports it as required
    if (probe.type == ProbeType::Interface && c.fluids.size() < 2)
      p.fail(p.raw("type"), "type", "an interface probe needs two fluids or more (`fluids:`)");
    if (p.has("phase")) {
      if (!phased) p.fail(p.raw("phase"), "phase", "only pressure, velocity, temperature, height, front, centroid and interface probes take a phase");
      probe.phase = fluid_index(p, "phase", c);
      probe.phase_name = c.fluids[probe.phase].name;
    }
    switch (probe.type) {
      case ProbeType::Pressure:
      case ProbeType::Temperature:
      case ProbeType::Velocity: probe.position = p.vector("position", d); break;
      case ProbeType::HeatFlux: {
        // A tank face (face: x-), or a solid (solid: name), whole or one face of its box.
        if (p.has("solid")) {
          probe.solid = p.text("solid");
          if (!solid_names.count(probe.solid)) p.fail(p.raw("solid"), "solid", "no solid named '" + probe.solid + "'");
        } else if (!p.has("face")) {
          p.fail(p.node(), "face", "is required: the tank face (x-, x+, y-, ...) or a solid (solid: name)");
        }
        if (p.has("face")) {
          const std::string face = p.text("face");
          probe.face = face_index(face, d);
          if (probe.face < 0) p.fail(p.raw("face"), "face", "'" + face + "' is not a face of this " + std::to_string(d) + "D case (x-, x+, y-, ...)");
          if (probe.solid.empty())
            if (auto why = tank_wall_missing(c, probe.face)) p.fail(p.raw("face"), "face", *why);
          if (shaped_solid(probe.solid)) p.fail(p.raw("face"), "face", "solid '" + probe.solid + "' is not a box: its heat flux is over its whole surface");
        }
        if (p.has("length") != p.has("temperature_difference"))
          p.fail(p.node(), p.has("length") ? "temperature_difference" : "length", "the Nusselt number needs both length and temperature_difference");
        if (p.has("length")) {
          probe.length = p.number("length");
          probe.temperature_difference = p.number("temperature_difference");
          if (!(probe.length > 0)) p.fail(p.raw("length"), "length", "must be > 0 [m]");
          if (probe.temperature_difference == 0) p.fail(p.raw("temperature_difference"), "temperature_difference", "must not be 0 [K]");
        }
        probe.conductivity = p.number("conductivity", c.fluids[0].thermal.conductivity);
        if (!(probe.conductivity > 0)) p.fail(p.raw("conductivity"), "conductivity", "must be > 0 [W/(m K)]");
        break;
      }
      case ProbeType::Height:
        probe.position = p.vector("position", d - 1);
        probe.connected = p.boolean("connected", false);
        break;
      case ProbeType::Force:
        probe.solid = p.text("solid");
        if (!solid_names.count(probe.solid)) p.fail(p.raw("solid"), "solid", "no solid named '" + probe.solid + "'");
        if (p.has("face")) {
          const std::string face = p.text("face");
          probe.face = face_index(face, d);
          if (probe.face < 0)
            p.fail(p.raw("face"), "face", "'" + face + "' is not a face of a " + std::to_string(d) + "D box (x-, x+, " +
                                              (d == 3 ? "y-, y+, z-, z+)" : "y-, y+)"));
          if (shaped_solid(probe.solid)) p.fail(p.raw("face"), "face", "solid '" + probe.solid + "' is not a box: its force is the whole solid's");
        }
        probe.viscous = p.boolean("viscous", false);
        break;
      case ProbeType::Body: {
        probe.solid = p.text("solid");
        if (!solid_names.count(probe.solid)) p.fail(p.raw("solid"), "solid", "no solid named '" + probe.solid + "'");
        bool floating = false;
        for (const SolidSpec& solid : c.solids)
          if (solid.name == probe.solid && solid.motion >= 0) floating = c.motions[solid.motion].floating >= 0;
        if (!floating) p.fail(p.raw("solid"), "solid", "solid '" + probe.solid + "' does not float (motion: floating)");
        break;
      }
      case ProbeType::WallPressure:
        read_wall_sensor(p, c, probe);
        // The sensor reads Adami's pressure with a static wall's (g - a_w) at a fixed point.
        if (on_moving_body(probe.position, c))
          p.fail(p.raw("position"), "position", "a wall_pressure sensor on a moving wall is not supported (it stays where it is)");
        break;
      case ProbeType::Centroid:
      case ProbeType::Interface:
      case ProbeType::Drive: break;
      case ProbeType::Front: {
        const std::string axis = p.text("axis", std::string("x"));
        probe.axis = axis == "x" ? 0 : axis == "y" ? 1 : axis == "z" ? 2 : -1;
        if (probe.axis < 0 || probe.axis >= d) p.fail(p.raw("axis"), "axis", "must be an axis of the case");
        probe.min_depth = p.number("min_depth", 0.0);
        if (!(probe.min_depth >= 0) || probe.min_depth >= c.tank_size[d - 1])
          p.fail(p.raw("min_depth"), "min_depth", "must be >= 0 and below the tank top");
        break;
      }
    }
    if (p.has("follow")) {
      // The probe rides with a moving body: a gauge on a sloshing tank's wall.
      if (probe.type != ProbeType::Pressure && probe.type != ProbeType::Velocity && probe.type != ProbeType::Height)
        p.fail(p.raw("follow"), "follow", "only pressure, velocity and height probes follow a moving body");
      const std::string body = p.text("follow");
      int motion = -1;
      if (body == "tank") motion = c.tank_motion;
      for (const SolidSpec& solid : c.solids)
        if (solid.name == body) motion = solid.motion;
      if (body != "tank" && !solid_names.count(body)) p.fail(p.raw("follow"), "follow", "no solid named '" + body + "' (or 'tank')");
      if (motion < 0) p.fail(p.raw("follow"), "follow", "'" + body + "' does not move (it has no motion)");
      probe.follow = motion;
    }
    p.finish();
    c.probes.push_back(probe);
  }
  if (c.probes.size() > 1000) root.fail(root.raw("probes"), "probes", "at most 1000 probes");
  {
    auto o = root.optional_child("output");
    c.output_interval = o.number("interval", 0.0);
    c.probe_interval = o.number("probe_interval", 0.0);
    c.checkpoint_every = o.integer("checkpoint_every", 0);
    c.checkpoint_keep_last = o.integer("checkpoint_keep_last", 2);
    c.checkpoint_keep_every = o.integer("checkpoint_keep_every", 0);
    if (c.output_interval < 0) o.fail(o.raw("interval"), "interval", "must be >= 0");
    if (c.probe_interval < 0) o.fail(o.raw("probe_interval"), "probe_interval", "must be >= 0");
    if (c.checkpoint_every < 0) o.fail(o.raw("checkpoint_every"), "checkpoint_every", "must be >= 0");
    if (c.checkpoint_keep_last < 0) o.fail(o.raw("checkpoint_keep_last"), "checkpoint_keep_last", "must be >= 0 (0: keep all)");
    if (c.checkpoint_keep_every < 0) o.fail(o.raw("checkpoint_keep_every"), "checkpoint_keep_every", "must be >= 0 (0: none)");
    o.finish();
  }
  {
    auto dcmp = root.optional_child("decomposition");
    c.balance_every = dcmp.integer("balance_every", 100);
    if (c.balance_every < 0) dcmp.fail(dcmp.raw("balance_every"), "balance_every", "must be >= 0 (0: never)");
    c.balanced_start = dcmp.choice<bool>("initial_layout", true, {{"balanced", true}, {"uniform", false}});
    dcmp.finish();
  }
  if (auto in = root.child("insitu")) {
    if (in->has("pipelines")) {
      const YAML::Node list = in->raw("pipelines");
      const std::filesystem::path folder = std::filesystem::path(file).parent_path();
      auto add = [&](const YAML::Node& entry) {
        if (!entry.IsScalar() || entry.Scalar().empty()) in->fail(entry, "pipelines", "expected a list of Catalyst script paths");
        const std::filesystem::path script(entry.Scalar());
        c.insitu_pipelines.push_back((script.is_absolute() ? script : folder / script).lexically_normal().string());
      };
      if (list.IsScalar()) {
        add(list);  // a single script without brackets
      } else if (list.IsSequence()) {
        for (std::size_t k = 0; k < list.size(); ++k) add(list[k]);
      } else {
        in->fail(list, "pipelines", "expected a list of Catalyst script paths");
      }
    }
    c.insitu_every = in->integer("every", 1);
    if (c.insitu_every < 1) in->fail(in->raw("every"), "every", "must be >= 1 (steps between in-situ runs)");
    c.insitu_timeout = in->number("timeout", c.insitu_timeout);
    if (!(c.insitu_timeout > 0) || !std::isfinite(c.insitu_timeout))
      in->fail(in->raw("timeout"), "timeout", "must be > 0 (seconds a pipeline may take on one in-situ step)");
    c.insitu_live_timeout = in->number("live_timeout", c.insitu_live_timeout);
    if (!(c.insitu_live_timeout > 0) || !std::isfinite(c.insitu_live_timeout))
      in->fail(in->raw("live_timeout"), "live_timeout", "must be > 0 (seconds a live peer may take to answer)");
    in->finish();
  }
  root.finish();
  return c;
}

}  // namespace

Case parse_case(const std::string& yaml_text, const std::string& file_name, const std::vector<std::string>& overrides) {
  YAML::Node root;
  try {
    // Every document is parsed: a second one would otherwise be ignored without a word.
    const std::vector<YAML::Node> docs = YAML::LoadAll(yaml_text);
    if (docs.size() > 1) {
      const int line = docs[1].Mark().line;
      throw CaseError(file_name + (line >= 0 ? ":" + std::to_string(line + 1) : std::string()) +
                      ": a second YAML document ('---'): a case file holds exactly one");
    }
    if (!docs.empty()) root = docs.front();
  } catch (const YAML::ParserException& e) {
    throw CaseError(file_name + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                    ": YAML syntax error: " + e.msg);
  }
  if (!root.IsMap()) throw CaseError(file_name + ": expected a YAML map of case keys at the top level");
  ReadContext ctx{file_name, {}, {}, {}};
  for (auto& o : overrides) ctx.overridden.emplace_back(apply_override(root, file_name, o), o);
  Section top(root, "", ctx);
  Case c = read(top, file_name);
  reject_unknown_keys(ctx);
  c.source_yaml = YAML::Dump(root);
  return c;
}

Case load_case(const std::string& path, const std::vector<std::string>& overrides) {
  std::string text;
  try {
    text = read_input_text(path, "the case file", kLargestCaseFile);
  } catch (const InputFileError& e) {
    throw CaseError(e.what());
  }
  return parse_case(text, path, overrides);
}

double highest_fluid_column(const Case& c) {
  const int v = c.dim - 1;
  double h = c.wet_bed;
  for (auto& b : c.fluid_blocks) h = std::max(h, b.max[v] - c.tank_origin[v]);
  if (c.tank_shape) h = std::min(h, c.tank_shape->hi[v] - c.tank_origin[v]);  // blocks cut to the vessel
  return h;
}

double sound_speed(const Case& c, int fluid) {
  if (c.fluids[fluid].sound_speed) return *c.fluids[fluid].sound_speed;
  double g = 0;
  for (int k = 0; k < c.dim; ++k) g += c.gravity[k] * c.gravity[k];
  g = std::sqrt(g);
  const double auto_c0 = 10.0 * std::sqrt(g * highest_fluid_column(c));
  return auto_c0 > 0 ? auto_c0 : 1.0;
}

namespace {
// Heat transfer's constants (physics/heat_transfer.hpp): one thermal entry per fluid, one for the
// tank, one per solid with thermal properties (the solids without share one that does not conduct);
// the tank faces' conditions.
void set_heat_params(const Case& c, PhysicsParams& P) {
  HeatParams& H = P.heat;
  H.on = true;
  // The Laplacian's normalisation (kernel_norm over the moment with eta^2) over the gradient's
  // (kernel_norm over the moment without).
  const auto moment = [&](double eta2) {
    return c.kernel == KernelType::WendlandC2 ? lattice_gradient_moment<WendlandC2>(c.dim, P.h, c.dp, eta2)
                                              : lattice_gradient_moment<CubicSpline>(c.dim, P.h, c.dp, eta2);
  };
  H.laplacian_scale = static_cast<float>(moment(0.0) / moment(P.eta2));
  H.wall_volume = static_cast<float>(std::pow(c.dp, c.dim));
  for (int k = 0; k < 3; ++k) H.gravity[k] = static_cast<float>(c.buoyancy_gravity[k]);
  int entries = 0;
  auto add = [&](const ThermalSpec& t, ThermalCondition condition) {
    if (entries >= kMaxThermalEntries)
      throw CaseError(c.file + ": key 'solids': at most " + std::to_string(kMaxThermalEntries) +
                      " materials with thermal properties (fluids, the tank and solids together)");
    ThermalMaterial& m = H.entry[entries];
    m.conductivity = static_cast<float>(t.conductivity);
    m.specific_heat = static_cast<float>(t.specific_heat);
    m.density = static_cast<float>(t.density);
    m.expansion = static_cast<float>(t.expansion);
    m.reference_temperature = static_cast<float>(t.reference_temperature.value_or(c.initial_temperature));
    m.condition = condition;
    return static_cast<std::uint8_t>(entries++);
  };
  for (std::size_t k = 0; k < c.fluids.size(); ++k) H.of[k] = add(c.fluids[k].thermal, ThermalCondition::Conducting);
  int tables = 0;
  for (std::size_t k = 0; k < c.fluids.size(); ++k) {
    if (c.fluids[k].thermal.viscosity.empty()) continue;
    if (tables >= kMaxViscosityTables)
      throw CaseError(c.file + ": key 'fluids': at most " + std::to_string(kMaxViscosityTables) + " fluids with a viscosity table");
    fill_viscosity_table(c.fluids[k].thermal.viscosity, H.viscosity_table[tables]);
    H.viscosity_table_of[k] = static_cast<std::uint8_t>(++tables);
    H.viscosity_varies = true;
  }
  H.of[P.materials.tank()] = add(c.tank_thermal, ThermalCondition::Conducting);
  int inert = -1;  // the shared entry of the solids without thermal properties
  for (std::size_t k = 0; k < c.solids.size(); ++k) {
    const ThermalSpec& t = c.solids[k].thermal;
    const std::uint8_t m = P.materials.solid(static_cast<int>(k));
    if (t.given) {
      H.of[m] = add(t, t.fixed ? ThermalCondition::Fixed : ThermalCondition::Conducting);
    } else {
      if (inert < 0) inert = add(ThermalSpec{}, ThermalCondition::Conducting);
      H.of[m] = static_cast<std::uint8_t>(inert);
    }
  }
  for (int m = P.materials.tank(); m < P.materials.count; ++m) {
    const ThermalMaterial& t = H.material(static_cast<std::uint8_t>(m));
    H.walls_conduct = H.walls_conduct || (t.condition == ThermalCondition::Conducting && t.conductivity > 0.0f);
  }
  // A face without a condition: the tank's own conduction when it conducts, else adiabatic.
  for (int f = 0; f < 6; ++f) {
    const FaceThermalSpec& s = c.tank_faces[f];
    const bool conducts = c.tank_thermal.conductivity > 0;
    H.face[f].kind = s.kind != ThermalCondition::Conducting ? s.kind : conducts ? ThermalCondition::Conducting : ThermalCondition::Adiabatic;
    H.face[f].value = static_cast<float>(s.value);
  }
}
}  // namespace

PhysicsParams physics_params(const Case& c) {
  PhysicsParams P;
  P.dim = c.dim;
  P.kernel = c.kernel;
  P.dp = static_cast<float>(c.dp);
  P.h = static_cast<float>(c.smoothing_ratio * c.dp);
  P.inv_h = 1.0f / P.h;
  P.inv_h2 = P.inv_h * P.inv_h;
  P.support2 = 4.0f * P.h * P.h;
  P.kernel_norm = c.kernel == KernelType::WendlandC2 ? WendlandC2::normalisation(c.dim, P.h)
                                                     : CubicSpline::normalisation(c.dim, P.h);
  const double moment = c.kernel == KernelType::WendlandC2 ? lattice_gradient_moment<WendlandC2>(c.dim, P.h, c.dp)
                                                          : lattice_gradient_moment<CubicSpline>(c.dim, P.h, c.dp);
  P.gradient_norm = static_cast<float>(P.kernel_norm / moment);
  P.eta2 = 0.01f * P.h * P.h;
  // Materials (physics/materials.hpp): the fluids, then the tank, then every solid.
  P.materials.fluids = static_cast<std::uint8_t>(c.fluids.size());
  P.materials.count = static_cast<std::uint8_t>(c.fluids.size() + 1 + c.solids.size());
  for (std::size_t k = 0; k < c.fluids.size(); ++k) {
    const FluidSpec& f = c.fluids[k];
    P.materials.fluid[k] = make_fluid(static_cast<float>(f.density), static_cast<float>(sound_speed(c, static_cast<int>(k))),
                                      static_cast<float>(f.tait_exponent), static_cast<float>(f.viscosity),
                                      static_cast<float>(f.density * std::pow(c.dp, c.dim)),
                                      static_cast<float>(f.background_pressure));
    if (P.materials.fluid[k].tait_b > P.materials.fluid[P.materials.reference].tait_b) P.materials.reference = static_cast<std::uint8_t>(k);
  }
  for (const SurfaceTensionSpec& st : c.surface_tension) {
    const float sigma = static_cast<float>(st.coefficient);
    P.surface_tension.sigma[st.a][st.b] = P.surface_tension.sigma[st.b][st.a] = sigma;
    for (int f : {st.a, st.b}) P.surface_tension.largest[f] = std::max(P.surface_tension.largest[f], sigma);
    P.surface_tension.on = P.surface_tension.on || sigma > 0.0f;
  }
  P.tension = c.tension;
  P.wall_tension = c.wall_tension;
  P.portable_eos = c.portable_eos;
  for (int k = 0; k < 3; ++k) {
    P.tank_lo[k] = static_cast<float>(c.tank_origin[k]);
    P.tank_hi[k] = static_cast<float>(c.tank_origin[k] + c.tank_size[k]);
    if (c.free_slip[k]) P.free_slip_axes = static_cast<std::uint8_t>(P.free_slip_axes | (1u << k));
  }
  // A box tank's faces: free_slip_axes and wall_shear (box_tank_frame); a shaped tank's surface and
  // the solids: each material's face_shear, through its particles' own frames (WallFrame).
  P.wall_shear = c.tank_shape ? WallShear::Laminar : c.wall_shear;
  auto set_face = [&P](std::uint8_t m, bool free_slip, WallShear shear) {
    const FaceShear f = free_slip ? FaceShear::FreeSlip : shear == WallShear::LogLaw ? FaceShear::LogLaw : FaceShear::NoSlip;
    P.materials.face_shear[m] = f;
    P.materials.face_frames = P.materials.face_frames || f != FaceShear::NoSlip;
    P.materials.faces_slide = P.materials.faces_slide || f == FaceShear::FreeSlip;
  };
  if (c.tank_shape) set_face(P.materials.tank(), c.shaped_tank_free_slip, c.wall_shear);
  for (std::size_t k = 0; k < c.solids.size(); ++k)
    set_face(P.materials.solid(static_cast<int>(k)), c.solids[k].free_slip, c.solids[k].wall_shear);
  if (c.tank_motion >= 0) P.materials.motion[P.materials.tank()] = static_cast<std::uint8_t>(c.tank_motion + 1);
  for (std::size_t k = 0; k < c.solids.size(); ++k)
    if (c.solids[k].motion >= 0) P.materials.motion[P.materials.solid(static_cast<int>(k))] = static_cast<std::uint8_t>(c.solids[k].motion + 1);
  // The walls' state at t = 0; the time loop sets it again before every step.
  MotionSet(c.motions, c.dim).set_step(P, 0.0, 0.0);
  P.artificial_viscosity = static_cast<float>(c.artificial_viscosity);
  P.wall_artificial_viscosity = static_cast<float>(c.wall_artificial_viscosity);
  P.delta = static_cast<float>(c.delta);
  P.diffusion = c.diffusion;
  P.flux = c.flux;
  P.pressure_difference = c.pressure_difference ? 1.0f : 0.0f;
  P.riemann_limiter = static_cast<float>(c.riemann_limiter);
  P.density_mode = c.density_mode;
  // SPS turbulence: the filter width is the particle spacing (turbulence.hpp).
  P.turbulence.on = c.sps;
  P.turbulence.smagorinsky2 = static_cast<float>(c.smagorinsky * c.dp * c.smagorinsky * c.dp);
  P.turbulence.isotropic = static_cast<float>(2.0 / 3.0 * c.sps_isotropic * c.dp * c.dp);
  P.shifting.enabled = c.shifting;
  P.shifting.coefficient = static_cast<float>(c.shifting_coefficient);
  P.shifting.mach = static_cast<float>(c.shifting_mach);
  // A summation density follows the positions by itself: the term is for continuity only.
  P.shifting.volume_consistent = c.shifting && c.shifting_volume_consistent && c.density_mode == DensityMode::Continuity;
  P.shifting.free_surface = c.shifting_free_surface;
  P.shifting.correct_velocity = c.shifting && c.shifting_correct_velocity;
  for (int k = 0; k < 3; ++k) {
    P.gravity[k] = static_cast<float>(c.gravity[k]);
    P.body_force[k] = static_cast<float>(c.body_force[k]);
  }
  if (c.zone.time > 0) {
    for (int k = 0; k < 3; ++k) {
      P.zone.lo[k] = static_cast<float>(c.zone.min[k]);
      P.zone.hi[k] = static_cast<float>(c.zone.max[k]);
      P.zone.velocity[k] = static_cast<float>(c.zone.velocity[k]);
    }
    P.zone.inv_time = static_cast<float>(1.0 / c.zone.time);
    P.zone.parabolic = c.zone.parabolic;
  }
  if (c.heat) set_heat_params(c, P);
  return P;
}


std::vector<std::string> material_names(const Case& c) {
  std::vector<std::string> names;
  for (const FluidSpec& f : c.fluids) names.push_back(f.name);
  names.push_back("tank");
  for (const SolidSpec& s : c.solids) names.push_back(s.name);
  return names;
}

}  // namespace spate
