#include "generator.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "../physics/eos.hpp"

namespace spate {

namespace {

// The lattice of particle sites: site i along an axis sits at origin + (i + 1/2) dp; the tank
// interior holds sites [0, n), walls sit at [-layers, 0) and [n, n + layers).
struct Sites {
  int dim;
  double dp;
  Vec3d origin;
  int n[3] = {1, 1, 1};
  int lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};  // all sites, walls included

  explicit Sites(const Case& c) : dim(c.dim), dp(c.dp), origin(c.tank_origin) {
    for (int a = 0; a < dim; ++a) {
      n[a] = static_cast<int>(std::lround(c.tank_size[a] / dp));
      const bool walls = !c.periodic[a];
      lo[a] = walls ? -c.wall_layers : 0;
      const bool top = a == dim - 1;
      hi[a] = n[a] + (walls && !(top && c.open_top) ? c.wall_layers : 0);
    }
  }
  double coord(int a, int i) const { return origin[a] + (i + 0.5) * dp; }
  int first_inside(int a, double v) const { return static_cast<int>(std::lround((v - origin[a]) / dp)); }
};

bool in_box(const Box& b, const double x[3], int dim) {
  for (int a = 0; a < dim; ++a)
    if (x[a] < b.min[a] || x[a] > b.max[a]) return false;
  return true;
}

// A shape's signed distance at the sites of one lattice column (the vertical axis runs innermost in
// the site loop). The distance is 1-Lipschitz: a site dz along the column from the last one
// queried is at least |d| - dz from the surface, on the same side. While that bound exceeds
// `margin` it is returned in place of the distance (with the right sign): the caller, whose
// thresholds lie within the margin, decides the site as the exact distance would, and a mesh
// case's sites cost a query only near the surface.
class ColumnDistance {
 public:
  double at(const Shape& shape, const double x[3], int dim, double margin) {
    const int v = dim - 1;
    if (valid_ && x[0] == column_[0] && (dim < 3 || x[1] == column_[1])) {
      const double bound = std::fabs(d_) - std::fabs(x[v] - along_);
      if (bound > margin) return d_ > 0 ? bound : -bound;
    }
    double n[3];
    valid_ = true;
    column_[0] = x[0], column_[1] = x[1], along_ = x[v];
    return d_ = shape.distance(x, n);
  }

 private:
  bool valid_ = false;
  double column_[2] = {0, 0}, along_ = 0, d_ = 0;
};

// One per shaped solid and fluid block, for the site loop; `surfaces`: the shape of each solid whose
// wall particles follow its surface (a box solid's as a box shape), null for the others.
struct SiteMemo {
  std::vector<ColumnDistance> solids, blocks;
  ColumnDistance tank;
  std::vector<ShapePtr> surfaces;
  explicit SiteMemo(const Case& c) : solids(c.solids.size()), blocks(c.fluid_blocks.size()), surfaces(c.solids.size()) {
    for (std::size_t k = 0; k < c.solids.size(); ++k)
      if (c.solids[k].surface_particles) surfaces[k] = solid_surface(c.solids[k], c.dim);
  }
};

// How far off the surface of a solid with surface-following wall particles the fluid's lattice
// sites start [dp]. Its first wall layer lies dp/2 behind the surface, and the lattice's sites lie
// at any distance from a slanted face: a quarter of dp keeps a row of sites that runs along the
// face itself (a 45-degree face through lattice sites) out of the first wall layer's reach (dp/2
// from it, against dp between lattice rows), and takes the fluid's first row a quarter of dp
// farther from the face than the lattice's own walls have it, on the mean.
constexpr double kSurfaceClearance = 0.25;

// Whether site x lies in the block: its box (boundaries included), its shape, its disc/sphere, or
// its box under a sinusoidal top face. `memo`: the block's column distances in the site loop.
bool in_block(const FluidBlock& b, const double x[3], int dim, ColumnDistance* memo = nullptr) {
  if (b.shape) {
    if (!in_box(b, x, dim)) return false;
    double n[3];
    return (memo ? memo->at(*b.shape, x, dim, 1e-9) : b.shape->distance(x, n)) <= 0.0;
  }
  if (b.radius > 0) {
    double r2 = 0.0;
    for (int a = 0; a < dim; ++a) r2 += (x[a] - b.centre[a]) * (x[a] - b.centre[a]);
    return r2 <= b.radius * b.radius;
  }
  if (b.wave_amplitude == 0.0 || b.wave_displaces) return in_box(b, x, dim);
  const int v = dim - 1;
  for (int a = 0; a < v; ++a)
    if (x[a] < b.min[a] || x[a] > b.max[a]) return false;
  const double top = b.max[v] + b.wave_amplitude * std::sin(2.0 * M_PI * (x[0] - b.min[0]) / b.wavelength);
  return x[v] >= b.min[v] && x[v] <= top;
}

// A site this close outside a shaped solid's surface [dp] is taken as under it: a surface through a
// plane of sites (a column face at a multiple of dp) must not lose that plane to the rounding of a
// mesh stored in float32 (STL); the box solids keep such sites too.
constexpr double kOnSurface = 1e-4;

// Whether site x is a particle of a shaped solid: under its surface, within wall_layers dp of it
// when hollow. The particles stay on the lattice (a staircase under a slanted face): moving them
// onto surfaces parallel to the face, or packing them there, was tried and made a still tank read
// 7-12% too much pressure on a 45-degree slope, against 0.7-1.9% for the lattice (docs/cases.md).
bool in_shaped_solid(const Case& c, const SolidSpec& solid, const double x[3], bool& inside, ColumnDistance& memo) {
  Box reach = solid.box;
  for (int a = 0; a < c.dim; ++a) reach.min[a] -= c.dp, reach.max[a] += c.dp;
  inside = false;
  if (!in_box(reach, x, c.dim)) return false;
  const double dist = memo.at(*solid.shape, x, c.dim, (c.wall_layers + 1) * c.dp);
  inside = dist < kOnSurface * c.dp;
  return inside && !(solid.hollow && dist < -c.wall_layers * c.dp);
}

// The material of the particle at site (i, j, k), if any (physics/materials.hpp: the fluid of the
// first block that holds it, else of the wet bed, then the tank, then solid k). Returns false for
// an empty site.
bool classify(const Case& c, const MaterialTable& M, const Sites& s, const int idx[3], std::uint8_t& kind, SiteMemo& memo) {
  const int d = c.dim;
  double x[3] = {0, 0, 0};
  for (int a = 0; a < d; ++a) x[a] = s.coord(a, idx[a]);
  if (c.tank_shape) {
    // A shaped tank: the sites outside its surface, within wall_layers dp of it, are its walls (as
    // a box tank's layers at dp/2, 3dp/2, ...), a site on the surface too (kOnSurface, as for a
    // solid); farther out nothing.
    const double dist = memo.tank.at(*c.tank_shape, x, d, (c.wall_layers + 1) * c.dp);
    if (dist > c.wall_layers * c.dp) return false;
    // Walls that follow the surface (surface_wall_particles below): the sites outside it, and the
    // fluid's within the clearance, stay empty.
    if (c.tank_surface_particles && dist > -kSurfaceClearance * c.dp) return false;
    if (dist > -kOnSurface * c.dp) {
      kind = M.tank();
      return true;
    }
  } else {
    bool interior = true;
    for (int a = 0; a < d; ++a) interior = interior && idx[a] >= 0 && idx[a] < s.n[a];
    if (!interior) {
      kind = M.tank();
      return true;
    }
  }
  for (std::size_t k = 0; k < c.solids.size(); ++k) {
    const SolidSpec& solid = c.solids[k];
    if (solid.surface_particles) {
      // Its particles follow its surface (surface_wall_particles below): its sites, and the fluid's within
      // the clearance, stay empty.
      Box reach = solid.box;
      for (int a = 0; a < d; ++a) reach.min[a] -= 2 * c.dp, reach.max[a] += 2 * c.dp;
      if (in_box(reach, x, d) && memo.solids[k].at(*memo.surfaces[k], x, d, 2 * c.dp) < kSurfaceClearance * c.dp) return false;
      continue;
    }
    if (solid.shape) {
      bool inside = false;
      if (in_shaped_solid(c, solid, x, inside, memo.solids[k])) {
        kind = M.solid(static_cast<int>(k));
        return true;
      }
      if (inside) return false;  // the hollow core
      continue;
    }
    if (!in_box(solid.box, x, d)) continue;
    if (solid.hollow) {
      // Keep sites within wall_layers of a face that touches fluid (the floor face does not).
      double depth = 1e30;
      for (int f = 0; f < 2 * d; ++f)
        if (f != 2 * (d - 1)) depth = std::min(depth, face_depth(solid.box, x, f));
      if (depth > c.wall_layers * c.dp) return false;
    }
    kind = M.solid(static_cast<int>(k));
    return true;
  }
  for (std::size_t k = 0; k < c.fluid_blocks.size(); ++k)
    if (in_block(c.fluid_blocks[k], x, d, &memo.blocks[k])) {
      kind = static_cast<std::uint8_t>(c.fluid_blocks[k].fluid);
      return true;
    }
  if (x[d - 1] - c.tank_origin[d - 1] < c.wet_bed) {
    kind = static_cast<std::uint8_t>(c.wet_bed_fluid);
    return true;
  }
  return false;
}

constexpr std::uint8_t kEmptySite = 0xff;  // no material has this index (at most 255 materials)

// Visits every particle site in generation order (the vertical axis innermost) with its material.
// `record`: the material of every site (kEmptySite for none) is appended there; `replay`: the
// materials are read from such a record instead of classified again (a shaped case's sites cost
// distance queries: generate_particles classifies them once, to count and then to fill).
template <class Visit>
void for_each_site(const Case& c, Visit&& visit, std::vector<std::uint8_t>* record = nullptr,
                   const std::vector<std::uint8_t>* replay = nullptr) {
  const Sites s(c);
  const MaterialTable M = physics_params(c).materials;
  SiteMemo memo(c);
  std::size_t site = 0;
  int idx[3];
  for (idx[0] = s.lo[0]; idx[0] < s.hi[0]; ++idx[0])
    for (idx[1] = s.lo[1]; idx[1] < s.hi[1]; ++idx[1])
      for (idx[2] = s.lo[2]; idx[2] < s.hi[2]; ++idx[2]) {
        std::uint8_t kind = kEmptySite;
        if (replay) {
          kind = (*replay)[site++];
        } else if (!classify(c, M, s, idx, kind, memo)) {
          kind = kEmptySite;
        }
        if (record) record->push_back(kind);
        if (kind != kEmptySite) visit(s, idx, kind);
      }
}

}  // namespace

double face_depth(const Box& b, const double x[3], int face) {
  const int a = face / 2;
  return face % 2 == 0 ? x[a] - b.min[a] : b.max[a] - x[a];
}

Lattice make_lattice(const Case& c) {
  Lattice L;
  L.dim = c.dim;
  // 0.1% above the support so that rounding in cell_of never hides a neighbour.
  const double support = 2.0 * c.smoothing_ratio * c.dp * 1.001;
  const Sites s(c);
  const Vec3d motion_bound = MotionSet(c.motions, c.dim).bound();
  for (int a = 0; a < 3; ++a) {
    if (a >= c.dim) {
      L.cells[a] = 1;
      L.cell_size[a] = 1.0f;
      L.inv_cell[a] = 1.0f;
      continue;
    }
    double lo = s.origin[a] + s.lo[a] * c.dp;
    double hi = s.origin[a] + s.hi[a] * c.dp;
    // Moving walls sweep beyond where they start: room for the farthest they can go.
    lo -= motion_bound[a];
    hi += motion_bound[a];
    if (c.periodic[a]) {
      const double period = c.tank_size[a];
      const int cells = static_cast<int>(std::floor(period / support));
      if (cells < 3)
        throw CaseError(c.file + ": key 'tank.size': the periodic extent holds " + std::to_string(cells) +
                        " cells of one kernel support; at least 3 are needed");
      L.periodic[a] = true;
      L.period[a] = static_cast<float>(period);
      L.origin[a] = static_cast<float>(c.tank_origin[a]);
      L.cells[a] = cells;
      L.cell_size[a] = static_cast<float>(period / cells);
    } else {
      if (a == c.dim - 1 && c.open_top) hi += c.headroom * c.tank_size[a];
      // One spare cell on either side: particles may never reach it, but a wall layer at the edge
      // must not be in the outermost column where a slab would have no room for its halo.
      L.origin[a] = static_cast<float>(lo - support);
      L.cells[a] = static_cast<int>(std::ceil((hi - lo) / support)) + 2;
      L.cell_size[a] = static_cast<float>(support);
    }
    L.inv_cell[a] = 1.0f / L.cell_size[a];
  }
  return L;
}

std::string geometry_signature(const Case& c) {
  const int d = c.dim;
  auto vec = [&](const Vec3d& v) {
    std::string s = "[";
    for (int a = 0; a < d; ++a) s += fmt::format("{}{:.17g}", a ? ", " : "", v[a]);
    return s + "]";
  };
  std::string s = fmt::format("dimensions: {}\ndp: {:.17g}\n", d, c.dp);
  s += "tank.origin: " + vec(c.tank_origin) + "\ntank.size: " + vec(c.tank_size) + "\n";
  s += fmt::format("tank.wall_layers: {}\ntank.open_top: {}\n", c.wall_layers, c.open_top);
  s += fmt::format("tank.periodic: [{}, {}, {}]\n", c.periodic[0], c.periodic[1], c.periodic[2]);
  if (c.tank_shape) s += "tank.shape: " + c.tank_shape->signature + "\n";
  if (c.tank_surface_particles) s += "tank.wall_particles: surface\n";
  for (std::size_t k = 0; k < c.fluid_blocks.size(); ++k) {
    s += fmt::format("fluid_blocks[{}]: {} to {}\n", k, vec(c.fluid_blocks[k].min), vec(c.fluid_blocks[k].max));
    if (c.fluid_blocks[k].shape) s += fmt::format("fluid_blocks[{}].shape: {}\n", k, c.fluid_blocks[k].shape->signature);
  }
  s += fmt::format("wet_bed: {:.17g}\n", c.wet_bed);
  for (std::size_t k = 0; k < c.solids.size(); ++k) {
    s += fmt::format("solids[{}]: {} to {}, hollow {}\n", k, vec(c.solids[k].box.min), vec(c.solids[k].box.max), c.solids[k].hollow);
    if (c.solids[k].shape) s += fmt::format("solids[{}].shape: {}\n", k, c.solids[k].shape->signature);
    if (c.solids[k].surface_particles) s += fmt::format("solids[{}].wall_particles: surface\n", k);
  }
  return s;
}

std::string geometry_hash(const Case& c) {
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a, 64 bits
  for (const unsigned char ch : geometry_signature(c)) h = (h ^ ch) * 1099511628211ull;
  return fmt::format("{:016x}", h);
}

OpenSides open_sides(const Case& c) {
  OpenSides o;
  if (!c.open_top) return o;
  const Sites s(c);
  const int v = c.dim - 1;
  o.open = true;
  o.vertical = v;
  o.fluids = physics_params(c).materials.fluids;
  o.top = static_cast<float>(s.origin[v] + s.hi[v] * c.dp);
  o.ceiling = static_cast<float>(s.origin[v] + s.hi[v] * c.dp + c.headroom * c.tank_size[v]);
  for (int a = 0; a < 3; ++a) {
    const bool bounded = a < c.dim && a != v && !c.periodic[a];
    o.lo[a] = bounded ? static_cast<float>(s.origin[a] + s.lo[a] * c.dp) : -INFINITY;
    o.hi[a] = bounded ? static_cast<float>(s.origin[a] + s.hi[a] * c.dp) : INFINITY;
  }
  return o;
}

namespace {

// Closed-form counts. Every kind of site is decided by boxes of site indices: outside the tank
// interior a wall; inside, the first rule whose box holds the site (solids in order, a hollow
// solid's inner box empty before its shell; then the fluid blocks and the wet bed; else empty).
// The box of a rule along an axis is found by binary search on the generator's own predicate
// (classify(), evaluated exactly as it evaluates it), so the counts equal the site loop's, and
// the sites are counted over a grid of index intervals cut at the boxes' edges: cost grows with
// the number of boxes, not of sites (spate info answers at once at any dp).
enum class SiteKind : std::uint8_t { Empty, Wall, Fluid };

struct IndexBox {
  std::int64_t lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};  // sites [lo, hi) per axis
  SiteKind kind = SiteKind::Empty;
  bool empty(int dim) const {
    for (int a = 0; a < dim; ++a)
      if (hi[a] <= lo[a]) return true;
    return false;
  }
};

// The sites i in [0, n) where `holds(i)` is true, for a predicate that is true on one interval
// (`holds` is monotone on either side of it: a box edge test on a monotone coordinate). `rising`
// tests the lower edge (false then true), `falling` the upper edge (true then false).
template <class Rising, class Falling>
void site_interval(std::int64_t n, Rising&& rising, Falling&& falling, std::int64_t& lo, std::int64_t& hi) {
  std::int64_t a = 0, b = n;  // first i with rising(i)
  while (a < b) {
    const std::int64_t m = a + (b - a) / 2;
    if (rising(m)) b = m;
    else a = m + 1;
  }
  lo = a;
  a = 0, b = n;  // first i with !falling(i)
  while (a < b) {
    const std::int64_t m = a + (b - a) / 2;
    if (!falling(m)) b = m;
    else a = m + 1;
  }
  hi = std::max(lo, a);
}

// Counts of the kinds over the interior box `all`: the first rule holding a site decides it.
// Recursion over the axes, each cut at the edges of the rules that overlap the current slice.
void count_first_match(const std::vector<const IndexBox*>& rules, const IndexBox& slice, int axis, int dim,
                       ParticleCounts& n) {
  if (axis >= dim || axis >= 3) {
    std::int64_t sites = 1;
    for (int a = 0; a < dim; ++a) sites *= slice.hi[a] - slice.lo[a];
    const SiteKind kind = rules.empty() ? SiteKind::Empty : rules.front()->kind;
    if (kind == SiteKind::Fluid) n.fluid += sites;
    if (kind == SiteKind::Wall) n.wall += sites;
    return;
  }
  std::vector<std::int64_t> cuts{slice.lo[axis], slice.hi[axis]};
  for (const IndexBox* r : rules) {
    if (r->lo[axis] > slice.lo[axis] && r->lo[axis] < slice.hi[axis]) cuts.push_back(r->lo[axis]);
    if (r->hi[axis] > slice.lo[axis] && r->hi[axis] < slice.hi[axis]) cuts.push_back(r->hi[axis]);
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  std::vector<const IndexBox*> inside;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    IndexBox part = slice;
    part.lo[axis] = cuts[k];
    part.hi[axis] = cuts[k + 1];
    inside.clear();
    for (const IndexBox* r : rules)
      if (r->lo[axis] <= part.lo[axis] && r->hi[axis] >= part.hi[axis]) inside.push_back(r);
    // Only rules up to the first that holds the whole remaining slice can decide anything.
    std::size_t keep = inside.size();
    for (std::size_t j = 0; j < inside.size(); ++j) {
      bool whole = true;
      for (int a = axis + 1; a < dim && a < 3; ++a) whole = whole && inside[j]->lo[a] <= part.lo[a] && inside[j]->hi[a] >= part.hi[a];
      if (whole) {
        keep = j + 1;
        break;
      }
    }
    inside.resize(keep);
    count_first_match(inside, part, axis + 1, dim, n);
  }
}

}  // namespace

bool has_shapes(const Case& c) {
  if (c.tank_shape) return true;
  for (const SolidSpec& solid : c.solids)
    if (solid.shape || solid.surface_particles) return true;
  for (const FluidBlock& b : c.fluid_blocks)
    if (b.shape) return true;
  return false;
}

namespace {
// Shapes have no closed form: the sites counted as the generator visits them (and recorded).
ParticleCounts count_sites(const Case& c, std::vector<std::uint8_t>* record) {
  ParticleCounts n;
  const MaterialTable M = physics_params(c).materials;
  if (record) {
    const Sites s(c);
    std::size_t all = 1;
    for (int a = 0; a < 3; ++a) all *= static_cast<std::size_t>(s.hi[a] - s.lo[a]);
    record->reserve(all);
  }
  for_each_site(c, [&](const Sites&, const int*, std::uint8_t kind) { (M.is_fluid(kind) ? n.fluid : n.wall) += 1; }, record);
  return n;
}

// The wall particles that follow a surface: a shaped tank's (Case::tank_surface_particles), then
// the solids' (SolidSpec::surface_particles) in their order, after every lattice site.
struct SurfaceParticle {
  std::array<double, 3> x;
  std::uint8_t kind;
};
std::vector<SurfaceParticle> surface_wall_particles(const Case& c) {
  std::vector<SurfaceParticle> out;
  const MaterialTable M = physics_params(c).materials;
  if (c.tank_surface_particles)
    for (const auto& x : surface_layers(*c.tank_shape, c.dp, c.wall_layers, /*outside=*/true, c.dim)) out.push_back(SurfaceParticle{x, M.tank()});
  for (std::size_t k = 0; k < c.solids.size(); ++k) {
    if (!c.solids[k].surface_particles) continue;
    for (const auto& x : surface_layers(*solid_surface(c.solids[k], c.dim), c.dp, c.wall_layers, /*outside=*/false, c.dim))
      out.push_back(SurfaceParticle{x, M.solid(static_cast<int>(k))});
  }
  return out;
}

// The materials of a shaped case's lattice sites, classified once. A run counts its particles for
// its memory estimate, again to check the generated set, and the generator fills from the same
// sites: a mesh case's classification (its distance queries) is most of its start-up, so the last
// one is kept, under a key of everything that decides a site, until the generator has used it.
struct SiteRecord {
  std::string key;
  std::vector<std::uint8_t> kinds;
  std::vector<SurfaceParticle> surface;  // off the lattice, after its sites
  ParticleCounts counts;
};
std::mutex site_record_mutex;
std::shared_ptr<const SiteRecord> site_record_cache;

std::string site_signature(const Case& c) {
  std::string s = geometry_signature(c) + fmt::format("fluids: {}\nwet_bed_fluid: {}\n", c.fluids.size(), c.wet_bed_fluid);
  for (const FluidBlock& b : c.fluid_blocks)
    s += fmt::format("block: fluid {}, centre {:.17g} {:.17g} {:.17g}, radius {:.17g}, wave {:.17g} {:.17g} {}\n", b.fluid, b.centre[0],
                     b.centre[1], b.centre[2], b.radius, b.wave_amplitude, b.wavelength, b.wave_displaces);
  return s;
}

std::shared_ptr<const SiteRecord> site_record(const Case& c) {
  std::string key = site_signature(c);
  {
    const std::lock_guard lock(site_record_mutex);
    if (site_record_cache && site_record_cache->key == key) return site_record_cache;
  }
  auto r = std::make_shared<SiteRecord>();
  r->key = std::move(key);
  r->counts = count_sites(c, &r->kinds);
  r->surface = surface_wall_particles(c);
  r->counts.wall += static_cast<std::int64_t>(r->surface.size());
  const std::lock_guard lock(site_record_mutex);
  site_record_cache = r;
  return r;
}

void forget_site_record() {
  const std::lock_guard lock(site_record_mutex);
  site_record_cache.reset();
}
}  // namespace

ParticleCounts count_particles(const Case& c) {
  if (has_shapes(c)) return site_record(c)->counts;
  const Sites s(c);
  const int d = c.dim;
  ParticleCounts n;
  // Walls: every site outside the interior.
  std::int64_t all = 1, interior = 1;
  for (int a = 0; a < d; ++a) {
    all *= s.hi[a] - s.lo[a];
    interior *= s.n[a];
  }
  n.wall = all - interior;

  IndexBox inner_all;
  for (int a = 0; a < d; ++a) inner_all.hi[a] = s.n[a];
  std::vector<IndexBox> boxes;
  auto in_box_along = [&](const Box& b, int a, IndexBox& out) {
    site_interval(
        s.n[a], [&](std::int64_t i) { return !(s.coord(a, static_cast<int>(i)) < b.min[a]); },
        [&](std::int64_t i) { return !(s.coord(a, static_cast<int>(i)) > b.max[a]); }, out.lo[a], out.hi[a]);
  };
  for (auto& solid : c.solids) {
    IndexBox box;
    box.kind = SiteKind::Wall;
    for (int a = 0; a < d; ++a) in_box_along(solid.box, a, box);
    if (solid.hollow) {
      // classify(): empty where the depth below every face but the floor exceeds the layers.
      IndexBox core = box;
      core.kind = SiteKind::Empty;
      const double layers = c.wall_layers * c.dp;
      for (int a = 0; a < d; ++a) {
        std::int64_t lo = 0, hi = 0;
        site_interval(
            s.n[a],
            [&](std::int64_t i) { return s.coord(a, static_cast<int>(i)) - solid.box.min[a] + (a == d - 1 ? 1e30 : 0.0) > layers; },
            [&](std::int64_t i) { return solid.box.max[a] - s.coord(a, static_cast<int>(i)) > layers; }, lo, hi);
        core.lo[a] = std::max(core.lo[a], lo);
        core.hi[a] = std::min(core.hi[a], hi);
      }
      if (!core.empty(d)) boxes.push_back(core);
    }
    if (!box.empty(d)) boxes.push_back(box);
  }
  for (auto& block : c.fluid_blocks) {
    IndexBox box;
    box.kind = SiteKind::Fluid;
    for (int a = 0; a < d; ++a) in_box_along(block, a, box);
    if (!box.empty(d)) boxes.push_back(box);
  }
  if (c.wet_bed > 0) {
    IndexBox bed = inner_all;
    bed.kind = SiteKind::Fluid;
    const int v = d - 1;
    site_interval(
        s.n[v], [](std::int64_t) { return true; },
        [&](std::int64_t i) { return s.coord(v, static_cast<int>(i)) - c.tank_origin[v] < c.wet_bed; }, bed.lo[v], bed.hi[v]);
    if (!bed.empty(d)) boxes.push_back(bed);
  }
  std::vector<const IndexBox*> rules;
  for (auto& b : boxes) rules.push_back(&b);
  if (interior > 0) count_first_match(rules, inner_all, 0, d, n);
  return n;
}

// Height of the free surface above site x at rest: the top of the highest fluid block over it, or
// the wet bed.
double rest_surface(const Case& c, const float* x) {
  const int v = c.dim - 1;
  double top = c.tank_origin[v] + c.wet_bed;
  for (auto& b : c.fluid_blocks) {
    bool over = true;
    for (int a = 0; a < v; ++a) over = over && x[a] >= b.min[a] && x[a] <= b.max[a];
    if (over) top = std::max(top, b.max[v]);
  }
  // A shaped tank cuts a block that reaches beyond it: the water stands at most to its top.
  if (c.tank_shape) top = std::min(top, c.tank_shape->hi[v]);
  return top;
}

// Several fluids: each fluid particle's density from the pressure of the layers above it,
//   p = p_b(top) + sum over the fluid sites above in its column of rho0 g dp (+ its own half),
// through the inverse equation of state of its own fluid, so that oil over water, or water under
// air, starts in hydrostatic balance with a continuous pressure. Sites are generated column by
// column, bottom to top (the vertical axis innermost), so each column is a run of consecutive
// particles, summed here from its top. A solid, a wall or an empty site in between starts a new
// stack at the background pressure of its top fluid.
namespace {
void layered_hydrostatic_density(const Case& c, const PhysicsParams& P, ParticleStore& p) {
  const int v = c.dim - 1;
  double g = 0;
  for (int a = 0; a < c.dim; ++a) g += c.gravity[a] * c.gravity[a];
  g = std::sqrt(g);
  auto same_column = [&](std::size_t a, std::size_t b) {
    for (int k = 0; k < v; ++k)
      if (p.pos[k][a] != p.pos[k][b]) return false;
    return true;
  };
  double pressure = 0.0;  // at the bottom edge of the particle above
  for (std::size_t n = p.size(); n-- > 0;) {
    if (!P.is_fluid(p.material[n])) continue;
    const FluidMaterial& m = P.materials.of(p.material[n]);
    const bool below_fluid = n + 1 < p.size() && P.is_fluid(p.material[n + 1]) && same_column(n, n + 1) &&
                             p.pos[v][n + 1] - p.pos[v][n] < 1.5 * c.dp;
    if (!below_fluid) pressure = m.background_pressure;  // the top of a stack
    const double half = 0.5 * m.rho0 * g * c.dp;
    p.density[n] = tait_density(static_cast<float>(pressure + half), m);
    pressure += 2.0 * half;
  }
}
}  // namespace

namespace {
// top_wave with start `displace`: the lattice was cut flat at y0 = max_v; every fluid particle now
// moves by the incompressible (potential-flow) displacement of the face's linear mode,
//   xi = grad phi,  phi = -(a/k) sin(k s) e^{-k (y - y0)} above y0,  +(a/k) sin(k s) e^{k (y - y0)} below,
// s = x - min_x, k = 2 pi / wavelength: the face goes to y0 + a sin(k s) (xi_y = a sin(k s) at y0
// from either side), the field is divergence-free (no density change) and decays over a wavelength
// away from the face. A lattice row can only hold a face cut at multiples of dp; this places it to
// a fraction of dp, so that a linear-regime instability starts from its own mode.
void displace_by_waves(const Case& c, const PhysicsParams& P, ParticleStore& p) {
  const int v = c.dim - 1;
  for (const FluidBlock& b : c.fluid_blocks) {
    if (!b.wave_displaces || b.wave_amplitude == 0.0) continue;
    const double k = 2.0 * M_PI / b.wavelength, a = b.wave_amplitude, y0 = b.max[v];
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (!P.is_fluid(p.material[i])) continue;
      const double s = k * (p.pos[0][i] - b.min[0]), dy = p.pos[v][i] - y0;
      const double decay = std::exp(-k * std::fabs(dy)), side = dy >= 0 ? -1.0 : 1.0;
      p.pos[0][i] = static_cast<float>(p.pos[0][i] + side * a * std::cos(s) * decay);
      p.pos[v][i] = static_cast<float>(p.pos[v][i] + a * std::sin(s) * decay);
    }
  }
}
}  // namespace

double initial_temperature(const Case& c, const MaterialTable& M, std::uint8_t kind, const double x[3]) {
  if (M.is_fluid(kind)) {
    for (const FluidBlock& b : c.fluid_blocks) {
      if (b.fluid != kind || !in_block(b, x, c.dim)) continue;
      if (!b.temperature) break;
      const TemperatureField& t = *b.temperature;
      const double wave = t.amplitude != 0 ? t.amplitude * std::sin(2.0 * M_PI * (x[t.axis] - c.tank_origin[t.axis]) / t.wavelength) : 0.0;
      return t.mean + wave;
    }
    return c.initial_temperature;
  }
  if (kind == M.tank()) return c.tank_thermal.temperature.value_or(c.initial_temperature);
  return c.solids[kind - M.tank() - 1].thermal.temperature.value_or(c.initial_temperature);
}

// The velocity at t = 0 of a fluid particle at x (FluidBlock::velocity): its block's, zero outside
// every block (the wet bed is at rest).
std::array<double, 3> initial_velocity(const Case& c, std::uint8_t kind, const double x[3]) {
  const int v = c.dim - 1;
  for (const FluidBlock& b : c.fluid_blocks) {
    if (b.fluid != kind || !in_block(b, x, c.dim)) continue;
    double scale = 1.0;
    if (b.parabolic) {
      const double s = (x[v] - b.min[v]) / (b.max[v] - b.min[v]);
      scale = 4.0 * s * (1.0 - s);
    }
    return {scale * b.velocity[0], scale * b.velocity[1], scale * b.velocity[2]};
  }
  return {0, 0, 0};
}

namespace {
// The frame of a shaped wall's particle at x (params.hpp WallFrame; the kWallFrame fields): the unit
// normal from the wall into the fluid and the particle's depth behind the surface, from the
// surface's signed distance (shape.hpp): a solid's outward normal, a shaped tank's inward one.
// The particles stand on the lattice, so the frame is what tells the wall treatment which way the
// face runs under a slanted or curved face.
void set_wall_frame(const Shape& surface, bool container, const double x[3], int dim, ParticleStore& p, std::size_t i) {
  double normal[3] = {0, 0, 0};
  const double dist = surface.distance(x, normal);
  const double sign = container ? -1.0 : 1.0;  // a solid's outward normal points into the fluid
  for (int a = 0; a < dim; ++a) p.wall_normal[a][i] = static_cast<float>(sign * normal[a]);
  p.wall_depth[i] = static_cast<float>(std::max(0.0, sign * -dist));
}
}  // namespace

ParticleStore generate_particles(const Case& c) {
  const bool shapes = has_shapes(c);
  // Shapes: every site's material, classified once (and no longer kept once filled from).
  const std::shared_ptr<const SiteRecord> sites = shapes ? site_record(c) : nullptr;
  if (shapes) forget_site_record();
  const ParticleCounts n = shapes ? sites->counts : count_particles(c);
  if (n.fluid == 0) throw CaseError(c.file + ": the case generates no fluid particles (check fluid_blocks, wet_bed and dp)");
  if (n.total() > 0xfffffff0LL) throw CaseError(c.file + ": key 'dp': more than 4e9 particles");
  ParticleStore p(c.dim);
  p.resize(static_cast<std::size_t>(n.total()));
  const PhysicsParams P = physics_params(c);
  double g = 0;
  for (int a = 0; a < c.dim; ++a) g += c.gravity[a] * c.gravity[a];
  g = std::sqrt(g);
  // Heat transfer: only a store made while the run carries the thermal fields has a temperature.
  const bool heat = c.heat && p.temperature.size() == p.size();
  // Shaped walls that slide or follow the log law: each particle's frame (set_wall_frame).
  const bool frames = P.materials.face_frames && p.wall_depth.size() == p.size();
  std::vector<ShapePtr> solid_shapes;
  if (frames)
    for (const SolidSpec& solid : c.solids) solid_shapes.push_back(solid_surface(solid, c.dim));
  // One particle of material `kind` at xs, the next in generation order.
  std::size_t i = 0;
  auto make = [&](const double xs[3], std::uint8_t kind) {
    if (i >= p.size()) {  // a miscount: reported below, never written past the arrays
      ++i;
      return;
    }
    for (int a = 0; a < c.dim; ++a) p.pos[a][i] = static_cast<float>(xs[a]);
    p.material[i] = kind;
    p.id[i] = static_cast<std::uint32_t>(i);
    if (heat) p.temperature[i] = static_cast<float>(initial_temperature(c, P.materials, kind, xs));
    if (frames && P.materials.face_shear[kind] != FaceShear::NoSlip) {
      const bool tank = kind == P.materials.tank();
      set_wall_frame(tank ? *c.tank_shape : *solid_shapes[kind - P.materials.tank() - 1], tank, xs, c.dim, p, i);
    }
    const FluidMaterial& fluid = P.materials.wall_fluid();
    p.density[i] = fluid.rho0;
    if (P.is_fluid(kind)) {
      const auto u = initial_velocity(c, kind, xs);
      for (int a = 0; a < c.dim; ++a) p.vel[a][i] = static_cast<float>(u[a]);
      const FluidMaterial& m = P.materials.of(kind);
      // Start from hydrostatic balance (inverse of eq. 9) rather than from a uniform density that
      // would first have to collapse into it, on top of the background pressure: a particle at the
      // free surface (or anywhere without gravity) starts at rho0 and p_b, as the several fluids'
      // stacks do (layered_hydrostatic_density). The continuity equation keeps the density a particle
      // starts with, so a start at p = 0 would cancel p_b for the whole run.
      float x[3] = {0, 0, 0};
      for (int a = 0; a < c.dim; ++a) x[a] = p.pos[a][i];
      const double depth = std::max(0.0, rest_surface(c, x) - x[c.dim - 1]);
      p.density[i] = tait_density(static_cast<float>(m.background_pressure + m.rho0 * g * depth), m);
    }
    ++i;
  };
  for_each_site(c, [&](const Sites& s, const int* idx, std::uint8_t kind) {
    const double xs[3] = {s.coord(0, idx[0]), c.dim > 1 ? s.coord(1, idx[1]) : 0.0, c.dim > 2 ? s.coord(2, idx[2]) : 0.0};
    make(xs, kind);
  }, nullptr, shapes ? &sites->kinds : nullptr);
  if (shapes)
    for (const auto& w : sites->surface) make(w.x.data(), w.kind);
  if (i != p.size()) throw std::logic_error("generate_particles: the site loop disagrees with count_particles");
  if (P.materials.multiphase()) layered_hydrostatic_density(c, P, p);
  displace_by_waves(c, P, p);  // after the column sums, which need the lattice
  p.set_owned(p.size());
  return p;
}

}  // namespace spate
