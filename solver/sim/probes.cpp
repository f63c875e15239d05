#include "probes.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "../case/generator.hpp"
#include "../backend/particle_updates.hpp"
#include "../particles/particle_access.hpp"
#include "../physics/dispatch.hpp"
#include "../physics/interpolation.hpp"
#include "../physics/wall_boundary.hpp"

namespace spate {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool owns_point(SlabWorker& w, const Vec3d& at) {
  const int column = w.lattice().cell_of(static_cast<float>(at[0]), 0);
  return w.grid().owns_column(column);
}

// Whether particle material m counts for a probe of `phase` (a fluid; -1: every fluid).
bool in_phase(const PhysicsParams& P, std::uint8_t m, int phase) { return phase < 0 ? P.is_fluid(m) : m == phase; }

// Shepard sums of `field` (nullptr: weights only) around a point this slab owns, over the fluid
// particles of `phase` (-1: every fluid).
template <class Kernel, int Dim>
ShepardSums<Dim> shepard(SlabWorker& w, const Vec3d& at, const FieldVector<float>* field, int phase) {
  ParticleStore& p = w.particles();
  const Lattice& L = w.lattice();
  Vec<Dim> x;
  int g[3] = {0, 0, 0};
  for (int a = 0; a < Dim; ++a) {
    x[a] = static_cast<float>(at[a]);
    g[a] = L.cell_of(x[a], a);
  }
  ShepardSums<Dim> s;
  w.grid().view().for_each_neighbour_range(g, [&](std::uint32_t b, std::uint32_t e) {
    for (std::uint32_t j = b; j < e; ++j)
      if (in_phase(w.params(), p.material[j], phase))
        accumulate_shepard<Kernel, Dim>(w.params(), x, load_vec<Dim>(p.pos, j), p.density[j], p.material[j], field ? (*field)[j] : 0.0f, s);
  });
  return s;
}

}  // namespace

double sample_pressure(SlabWorker& w, const Vec3d& at, int phase) {
  if (!owns_point(w, at)) return kNaN;
  double out = 0.0;
  dispatch_kernel_dim(w.params(), [&]<class Kernel, int Dim>() {
    const auto s = shepard<Kernel, Dim>(w, at, &w.particles().pressure, phase);
    out = s.weight > 0 ? s.value / s.weight : 0.0;
  });
  return out;
}

double sample_temperature(SlabWorker& w, const Vec3d& at, int phase) {
  if (!owns_point(w, at)) return kNaN;
  double out = kNaN;
  dispatch_kernel_dim(w.params(), [&]<class Kernel, int Dim>() {
    const auto s = shepard<Kernel, Dim>(w, at, &w.particles().temperature, phase);
    if (s.weight > 0) out = s.value / s.weight;
  });
  return std::isnan(out) ? 0.0 : out;  // owned but dry: 0, as the pressure
}

std::vector<double> sample_velocity(SlabWorker& w, const Vec3d& at, int phase) {
  const int d = w.lattice().dim;
  std::vector<double> v(d, kNaN);
  if (!owns_point(w, at)) return v;
  dispatch_kernel_dim(w.params(), [&]<class Kernel, int Dim>() {
    for (int k = 0; k < Dim; ++k) {
      const auto s = shepard<Kernel, Dim>(w, at, &w.particles().vel[k], phase);
      v[k] = s.weight > 0 ? s.value / s.weight : 0.0;
    }
  });
  return v;
}

// Fill fraction (the Shepard weight sum) sampled every dp/4 up the gauge's vertical line, from the
// tank floor to the top of the domain; the surface is where it crosses 0.5, placed by linear
// interpolation between the two samples around the crossing, so that the height follows the
// particles continuously (no dp/4 steps). `connected`: the top of the water standing on the floor
// (the first crossing above the lowest wet sample, which must lie within the kernel support 2h of
// the floor), so that spray, an overtopping jet or drops above it are ignored; otherwise the
// highest crossing. 0 when dry.
double sample_height(SlabWorker& w, const ProbeSpec& gauge, const Case& c, std::optional<double> floor_at) {
  const int v = c.dim - 1;
  Vec3d at = gauge.position;
  at[v] = 0;
  if (!owns_point(w, at)) return kNaN;
  const double floor = floor_at.value_or(c.tank_origin[v]);
  const double top = w.lattice().upper(v) - 1e-6;
  const double step = c.dp / 4;
  const int last = static_cast<int>(std::ceil((top - floor) / step));  // samples 0..last
  auto z = [&](int k) { return std::min(floor + k * step, top); };
  double height = 0.0;
  dispatch_kernel_dim(w.params(), [&]<class Kernel, int Dim>() {
    auto fill = [&](int k) {
      at[v] = z(k);
      return shepard<Kernel, Dim>(w, at, nullptr, gauge.phase).weight;
    };
    // Sample k is wet, k + 1 dry: where the straight line between them crosses 0.5.
    auto crossing = [&](int k, double wet, double dry) { return z(k) + (wet - 0.5) / (wet - dry) * (z(k + 1) - z(k)) - floor; };
    if (gauge.connected) {
      const int reach = std::min(last, static_cast<int>(std::ceil(2.0 * w.params().h / step)));
      int k = 0;
      double wk = fill(0);
      while (wk < 0.5 && k < reach) wk = fill(++k);
      if (wk < 0.5) return;  // dry at the floor
      for (; k < last; ++k) {
        const double next = fill(k + 1);
        if (next < 0.5) {
          height = crossing(k, wk, next);
          return;
        }
        wk = next;
      }
      height = z(last) - floor;
      return;
    }
    double above = 0.0;
    for (int k = last; k >= 0; --k) {
      const double wk = fill(k);
      if (wk >= 0.5) {
        height = k == last ? z(last) - floor : crossing(k, wk, above);
        return;
      }
      above = wk;
    }
  });
  return height;
}

Vec3d followed_position(const ProbeSpec& gauge, const Case& c, const MotionSet& motions, double time) {
  const int v = c.dim - 1;
  Vec3d at = gauge.position;
  if (gauge.type == ProbeType::Height) at[v] = c.tank_origin[v];
  if (c.dim == 2) at[2] = 0.0;
  Vec3d out = moved_point(motions.spec(gauge.follow), motions.sample(gauge.follow, time), at);
  for (int k = c.dim; k < 3; ++k) out[k] = 0.0;
  return out;
}

// The same for a floating solid: x(t) = c(t) + R(t) (x(0) - c(0)), its centre of mass c and its turn
// R since t = 0 as its dynamics have them now.
Vec3d followed_position(const ProbeSpec& gauge, const Case& c, const RigidBodies& bodies) {
  const int b = c.motions[gauge.follow].floating;
  const BodyState& s = bodies.state(b);
  Vec3d r = gauge.position;
  if (gauge.type == ProbeType::Height) r[c.dim - 1] = c.tank_origin[c.dim - 1];
  for (int k = 0; k < 3; ++k) r[k] -= c.bodies[b].centre_of_mass[k];
  Vec3d out{0, 0, 0};
  for (int i = 0; i < c.dim; ++i) out[i] = s.centre[i] + s.rotation[i][0] * r[0] + s.rotation[i][1] * r[1] + s.rotation[i][2] * r[2];
  return out;
}

std::vector<Vec3d> sensor_points(const ProbeSpec& sensor, int dim, double dp) {
  const Vec3d& c = sensor.position;
  const Vec3d& n = sensor.normal;
  if (!(sensor.diameter > 0)) return {c};
  const double D = sensor.diameter;
  const int m = std::max(1, static_cast<int>(std::ceil(D / (dp / 4))));
  auto offset = [&](int i) { return ((i + 0.5) / m - 0.5) * D; };
  std::vector<Vec3d> out;
  if (dim == 2) {
    const Vec3d t{-n[1], n[0], 0};  // along the face
    for (int i = 0; i < m; ++i) out.push_back(Vec3d{c[0] + offset(i) * t[0], c[1] + offset(i) * t[1], 0});
    return out;
  }
  // Two unit tangents: e x n with e the axis least aligned with n, then n x t1.
  int e = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(n[k]) < std::fabs(n[e])) e = k;
  Vec3d a{0, 0, 0};
  a[e] = 1;
  Vec3d t1{a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2], a[0] * n[1] - a[1] * n[0]};
  const double l = std::sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
  for (auto& x : t1) x /= l;
  const Vec3d t2{n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]};
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = offset(i), v = offset(j);
      if (u * u + v * v > 0.25 * D * D) continue;
      out.push_back(Vec3d{c[0] + u * t1[0] + v * t2[0], c[1] + u * t1[1] + v * t2[1], c[2] + u * t1[2] + v * t2[2]});
    }
  return out;
}

std::vector<double> sample_wall_pressure(SlabWorker& w, const std::vector<Vec3d>& points) {
  std::vector<double> out(points.size(), kNaN);
  ParticleStore& p = w.particles();
  const Lattice& L = w.lattice();
  const PhysicsParams& P = w.params();
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (!owns_point(w, points[k])) continue;
      Vec<Dim> x;
      int g[3] = {0, 0, 0};
      for (int a = 0; a < Dim; ++a) {
        x[a] = static_cast<float>(points[k][a]);
        g[a] = L.cell_of(x[a], a);
      }
      WallSums<Dim> sums;
      w.grid().view().for_each_neighbour_range(g, [&](std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t j = b; j < e; ++j)
          if (P.is_fluid(p.material[j])) accumulate_wall_pair<Kernel, Dim>(P, x, load_state<Dim>(p, j), sums);
      });
      out[k] = sums.w > 0.0f ? adami_pressure(P, sums, zero_vec<Dim>()) : 0.0;
    }
  });
  return out;
}

double MovingAverage::add(double t, double v) {
  samples_.emplace_back(t, v);
  if (!(window_ > 0) || samples_.size() == 1) return v;
  const double start = t - window_;
  // Keep one sample at or before the window's start.
  while (samples_.size() > 2 && samples_[1].first <= start) samples_.pop_front();
  double integral = 0.0, from = std::max(start, samples_.front().first);
  for (std::size_t k = 1; k < samples_.size(); ++k) {
    const auto [t0, v0] = samples_[k - 1];
    const auto [t1, v1] = samples_[k];
    if (t1 <= from) continue;
    const double a = std::max(t0, from);
    const auto at = [&](double s) { return t1 > t0 ? v0 + (v1 - v0) * (s - t0) / (t1 - t0) : v1; };
    integral += 0.5 * (at(a) + v1) * (t1 - a);
  }
  const double span = t - from;
  return span > 0 ? integral / span : v;
}

double front_level(const ProbeSpec& front, const Case& c) {
  if (!(front.min_depth > 0)) return -std::numeric_limits<double>::infinity();
  return c.tank_origin[c.dim - 1] + front.min_depth - 0.5 * c.dp;
}

std::pair<double, double> local_interface_extent(SlabWorker& w, const Case& c, int phase) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::pair<double, double> extent{kInf, -kInf};
  const int d = c.dim, v = d - 1;
  const double spacing = d == 2 ? c.dp / 2 : c.dp;  // between lines
  const double step = c.dp / 4;                    // up a line
  const double floor = c.tank_origin[v];
  const double top = w.lattice().upper(v) - 1e-6;
  const int last = static_cast<int>(std::ceil((top - floor) / step));
  int lines[2] = {1, 1};
  for (int a = 0; a < v; ++a) lines[a] = std::max(1, static_cast<int>(std::lround(c.tank_size[a] / spacing)));
  dispatch_kernel_dim(w.params(), [&]<class Kernel, int Dim>() {
    for (int i = 0; i < lines[0]; ++i)
      for (int j = 0; j < lines[1]; ++j) {
        Vec3d at{0, 0, 0};
        at[0] = c.tank_origin[0] + (i + 0.5) * c.tank_size[0] / lines[0];
        if (d == 3) at[1] = c.tank_origin[1] + (j + 0.5) * c.tank_size[1] / lines[1];
        if (!owns_point(w, at)) continue;
        // The phase's fraction at sample k, NaN where there is no fluid.
        auto fraction = [&](int k) {
          at[v] = std::min(floor + k * step, top);
          const double all = shepard<Kernel, Dim>(w, at, nullptr, -1).weight;
          return all >= 0.5 ? shepard<Kernel, Dim>(w, at, nullptr, phase).weight / all : kNaN;
        };
        double below = fraction(0);
        for (int k = 0; k < last; ++k) {
          const double above = fraction(k + 1);
          if (!std::isnan(below) && !std::isnan(above) && (below - 0.5) * (above - 0.5) <= 0 && below != above) {
            const double y = floor + (k + (below - 0.5) / (below - above)) * step;
            extent.first = std::min(extent.first, y);
            extent.second = std::max(extent.second, y);
          }
          below = above;
        }
      }
  });
  return extent;
}

double local_front(SlabWorker& w, int axis, double lowest, int phase) {
  const ParticleStore& p = w.particles();
  const int v = p.dim() - 1;
  double front = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < p.owned(); ++i)
    if (in_phase(w.params(), p.material[i], phase) && p.pos[v][i] >= lowest) front = std::max(front, static_cast<double>(p.pos[axis][i]));
  return front;
}

std::vector<double> sample_centroid(SlabWorker& w, int phase) {
  // Exact integer sums of fixed-point coordinates and velocities (2^-28 m, 2^-28 m/s: below a
  // float's resolution at 1 m), so that the centroid does not depend on the split or the order.
  constexpr double kScale = 268435456.0;  // 2^28
  const ParticleStore& p = w.particles();
  const int d = p.dim();
  std::vector<std::int64_t> sums(1 + 2 * d, 0);
  for (std::size_t i = 0; i < p.owned(); ++i) {
    if (!in_phase(w.params(), p.material[i], phase)) continue;
    ++sums[0];
    for (int k = 0; k < d; ++k) {
      sums[1 + k] += std::llround(p.pos[k][i] * kScale);
      sums[1 + d + k] += std::llround(p.vel[k][i] * kScale);
    }
  }
  w.transport().sum(sums);
  std::vector<double> row(2 * d, kNaN);
  if (sums[0] > 0)
    for (int k = 0; k < 2 * d; ++k) row[k] = static_cast<double>(sums[1 + k]) / kScale / static_cast<double>(sums[0]);
  return row;
}

namespace {

// Calls visit(c) for the owned cells in order; only for those that hold a point of `region` when it
// is given.
template <class Visit>
void for_owned_cells(const CellGrid& grid, const Box* region, Visit&& visit) {
  if (!region) {
    for (std::uint32_t c = 0; c < grid.owned_cell_count(); ++c) visit(c);
    return;
  }
  const Lattice& L = grid.lattice();
  int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (int a = 0; a < L.dim; ++a) {
    lo[a] = std::max(L.cell_of(static_cast<float>(region->min[a]), a), 0);
    hi[a] = std::min(L.cell_of(static_cast<float>(region->max[a]), a), L.cells[a] - 1);
  }
  lo[0] = std::max(lo[0], grid.owned_lo()), hi[0] = std::min(hi[0], grid.owned_hi() - 1);
  for (int x = lo[0]; x <= hi[0]; ++x)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int z = lo[2]; z <= hi[2]; ++z)
        if (const std::uint32_t c = grid.local_cell(x, y, z); c != CellGrid::kOutside && c < grid.owned_cell_count()) visit(c);
}

// The force of fluid particle f on wall particle w through every pair term (pressure, artificial
// and laminar viscosity, and the interface and Riemann options' terms when on): minus m_f times
// the acceleration that w gives f in the fluid's own pair terms, so that the wall takes exactly
// what the fluid loses (its momentum is conserved pair by pair). The moving-wall and Riemann forms
// of the terms give the plain ones' values when walls are at rest and the options off; Gamma7 =
// true whatever the fluid's exponent, as the acceleration does not depend on it (only the density
// diffusion's rate does). With SPS turbulence the wall also takes the SPS stress's pair term
// (turbulence.hpp: the wall carries f's stress), from the stress of the last rates.
template <class Kernel, int Dim, bool Multiphase>
Vec<Dim> wall_pair_reaction(const PhysicsParams& P, const ParticleStore& p, std::uint32_t f, std::uint32_t w) {
  const ParticleState<Dim> sf = load_state<Dim>(p, f);
  ParticleState<Dim> sw = load_state<Dim>(p, w);
  sw.w = boundary_velocity<Dim>(P, sw);
  sw.w_av = sliding_velocity<Dim>(P, p, w, sw);
  const FluidMaterial& M = P.materials.of(sf.material);
  FluidRates<Dim> r;
  if constexpr (Multiphase)
    r = multiphase_pair_terms<Kernel, Dim, true, true, true>(P, M, sf, sw, particle_neighbour_fluid(P, p, w), particle_viscosity(P, p, f));
  else
    r = fluid_pair_terms<Kernel, Dim, true, true, true>(P, M, sf, sw);
  // (A store read back from a snapshot by spate post has no stress: the SPS term is left out there.)
  if (P.turbulence.on && p.sps_stress[0].size() == p.size()) {
    const SpsStress<Dim> T = load_sps_stress<Dim>(p, f);
    r.acc += sps_pair_acceleration<Kernel, Dim>(P, sf.x, T, sw.x, T, M.mass);
  }
  return (-M.mass) * r.acc;
}

// Calls fn(i, f, v) with the pressure force f[3] of the fluid on every owned particle i of material
// `kind` (a solid) and, when Viscous, the rest of the fluid's pair force on it v[3]
// (wall_pair_reaction less the pressure: its viscous stresses; else zeros). For one face of its box
// (face >= 0): only the particles less than a kernel support below that face (the fluid beyond
// the face is all they can reach through it). Only in the cells that hold a point of `region`,
// when it is given.
template <bool Viscous = false, class Fn>
void for_each_solid_force(SlabWorker& w, std::uint8_t kind, const Box& box, int face, Fn&& fn, const Box* region = nullptr) {
  ParticleStore& p = w.particles();
  const CellGrid& grid = w.grid();
  const PhysicsParams& P = w.params();
  const bool multiphase = pair_loop_flags(P).multiphase;
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    const CellGridView view = grid.view();
    for_owned_cells(grid, region, [&](std::uint32_t c) {
      int g[3];
      grid.global_coords(c, g);
      for (std::uint32_t i = grid.begin(c); i < grid.end(c); ++i) {
        if (p.material[i] != kind) continue;
        if (face >= 0) {
          const double x[3] = {p.pos[0][i], p.pos[1][i], Dim == 3 ? p.pos[2][i] : 0.0};
          if (face_depth(box, x, face) >= 2.0 * P.h) continue;
        }
        const auto wi = load_state<Dim>(p, i);
        Vec<Dim> f = zero_vec<Dim>(), total = zero_vec<Dim>();
        view.for_each_neighbour_range(g, [&](std::uint32_t b, std::uint32_t e) {
          for (std::uint32_t j = b; j < e; ++j) {
            if (!P.is_fluid(p.material[j])) continue;
            f += wall_pressure_force<Kernel, Dim>(P, wi, load_state<Dim>(p, j));
            if constexpr (Viscous) {
              if (distance_squared<Dim>(wi.x, p.pos, j) >= P.support2) continue;
              total += multiphase ? wall_pair_reaction<Kernel, Dim, true>(P, p, j, i) : wall_pair_reaction<Kernel, Dim, false>(P, p, j, i);
            }
          }
        });
        float out[3] = {0, 0, 0}, viscous[3] = {0, 0, 0};
        for (int k = 0; k < Dim; ++k) out[k] = f[k];
        if constexpr (Viscous)
          for (int k = 0; k < Dim; ++k) viscous[k] = total[k] - f[k];
        fn(i, out, viscous);
      }
    });
  });
}

// The pressure force of the fluid on every owned particle of material `kind` (a solid) and its
// viscous part (zeros unless `viscous`), as (id, fx, fy, fz, vx, vy, vz) records; for one face of its box (face >= 0), the component along the face's
// axis (a particle near an edge gives each of its faces that face's component).
Bytes solid_force_records(SlabWorker& w, std::uint8_t kind, const Box& box, int face, bool viscous) {
  Bytes out;
  const ParticleStore& p = w.particles();
  auto record = [&](std::uint32_t i, const float f[3], const float v[3]) {
    float rec[7] = {0, 0, 0, 0, 0, 0, 0};
    std::memcpy(&rec[0], &p.id[i], sizeof(float));
    for (int k = 0; k < 3; ++k) {
      const bool along = face < 0 || k == face / 2;
      rec[1 + k] = along ? f[k] : 0.0f;
      rec[4 + k] = along ? v[k] : 0.0f;
    }
    out.insert(out.end(), reinterpret_cast<char*>(rec), reinterpret_cast<char*>(rec) + sizeof rec);
  };
  if (viscous) for_each_solid_force<true>(w, kind, box, face, record);
  else for_each_solid_force<false>(w, kind, box, face, record);
  return out;
}

// The force and the torque about `centre` of the fluid on every owned particle of a floating solid
// (pressure and viscous: every pair term's reaction, so that the body takes what the fluid loses),
// as (id, fx, fy, fz, tx, ty, tz) records, in double.
struct LoadRecord {
  std::uint32_t id;
  double v[6];
};
Bytes body_load_records(SlabWorker& w, std::uint8_t kind, const std::array<double, 3>& centre, double reach) {
  Bytes out;
  const ParticleStore& p = w.particles();
  const int d = w.lattice().dim;
  // Only the cells the body can be in: within its reach of its centre (and a cell for rounding);
  // all cells when an axis is periodic (the body's particles may lie across the period).
  const Lattice& L = w.grid().lattice();
  Box region;
  bool periodic = false;
  for (int k = 0; k < d; ++k) {
    const double margin = reach + L.cell_size[k];
    region.min[k] = centre[k] - margin, region.max[k] = centre[k] + margin;
    periodic = periodic || L.periodic[k];
  }
  for_each_solid_force<true>(w, kind, Box{}, -1, [&](std::uint32_t i, const float f[3], const float v[3]) {
    LoadRecord rec{p.id[i], {f[0] + v[0], f[1] + v[1], f[2] + v[2], 0, 0, 0}};
    double r[3] = {0, 0, 0};
    for (int k = 0; k < d; ++k) r[k] = static_cast<double>(p.pos[k][i]) - centre[k];
    rec.v[3] = r[1] * rec.v[2] - r[2] * rec.v[1];
    rec.v[4] = r[2] * rec.v[0] - r[0] * rec.v[2];
    rec.v[5] = r[0] * rec.v[1] - r[1] * rec.v[0];
    out.insert(out.end(), reinterpret_cast<char*>(&rec), reinterpret_cast<char*>(&rec) + sizeof rec);
  }, periodic ? nullptr : &region);
  return out;
}

// Heat into the fluid through a tank face (solid empty) or a solid (whole, or one face of its box),
// per owned fluid particle, as (id, watts, 0, 0) records (2D: watts per metre of depth): the
// conduction from the face's wall particles, the same pair terms as the fluid's rate
// (heat_pair_term), times the particle's volume.
Bytes heat_flux_records(SlabWorker& w, const ProbeSpec& probe, const Case& c) {
  Bytes out;
  ParticleStore& p = w.particles();
  const PhysicsParams& P = w.params();
  const CellGrid& grid = w.grid();
  int solid = -1;
  for (std::size_t k = 0; k < c.solids.size(); ++k)
    if (c.solids[k].name == probe.solid) solid = static_cast<int>(k);
  // Whether wall particle j is on the probed surface.
  auto on_surface = [&](std::uint32_t j) {
    const std::uint8_t m = p.material[j];
    double x[3] = {0, 0, 0};
    for (int a = 0; a < c.dim; ++a) x[a] = p.pos[a][j];
    if (solid >= 0) {
      if (m != P.materials.solid(solid)) return false;
      return probe.face < 0 || face_depth(c.solids[solid].box, x, probe.face) < 2.0 * P.h;
    }
    if (m != P.materials.tank()) return false;
    float xf[3] = {0, 0, 0};
    for (int a = 0; a < c.dim; ++a) xf[a] = p.pos[a][j];
    const ThermalFace f = thermal_face(P.tank_lo, P.tank_hi, xf, c.dim);
    return f.axis >= 0 && f.index() == probe.face;
  };
  dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
    const CellGridView view = grid.view();
    for (std::uint32_t cell = 0; cell < grid.owned_cell_count(); ++cell) {
      int g[3];
      grid.global_coords(cell, g);
      for (std::uint32_t i = grid.begin(cell); i < grid.end(cell); ++i) {
        if (!P.is_fluid(p.material[i])) continue;
        const ThermalMaterial& Mi = P.heat.material(p.material[i]);
        const Vec<Dim> xi = load_vec<Dim>(p.pos, i);
        float sum = 0.0f;
        bool near = false;
        view.for_each_neighbour_range(g, [&](std::uint32_t b, std::uint32_t e) {
          for (std::uint32_t j = b; j < e; ++j)
            if (!P.is_fluid(p.material[j]) && distance_squared<Dim>(xi, p.pos, j) < P.support2 && on_surface(j)) {
              sum += heat_pair_term<Kernel, Dim>(P, p, Mi, xi, p.temperature[i], j);
              near = true;
            }
        });
        if (!near) continue;
        // sum is the surface's share of rho_i c_i dT_i/dt [W/m^3]: times V_i, the watts into i.
        float rec[4] = {0, 0, 0, 0};
        std::memcpy(&rec[0], &p.id[i], sizeof(float));
        rec[1] = sum * P.materials.of(p.material[i]).mass / p.density[i];
        out.insert(out.end(), reinterpret_cast<char*>(rec), reinterpret_cast<char*>(rec) + sizeof rec);
      }
    }
  });
  return out;
}

// The area of the surface a heat_flux probe integrates over [m^2] (2D: its length, per metre of
// depth): a tank face, a solid's box face, or its whole surface.
double heat_flux_area(const ProbeSpec& probe, const Case& c) {
  Vec3d size = c.tank_size;
  for (const SolidSpec& s : c.solids)
    if (s.name == probe.solid) {
      if (s.shape) return s.shape->area;  // shapes take no face (the loader says so)
      for (int a = 0; a < 3; ++a) size[a] = s.box.max[a] - s.box.min[a];
    }
  auto face_area = [&](int axis) {
    double a = 1.0;
    for (int k = 0; k < c.dim; ++k)
      if (k != axis) a *= size[k];
    return a;
  };
  if (probe.face >= 0) return face_area(probe.face / 2);
  double total = 0.0;
  for (int axis = 0; axis < c.dim; ++axis) total += 2.0 * face_area(axis);
  return total;
}

// Values that each belong to one slab (NaN elsewhere), gathered: element k from the slab that has a
// number there (0 if none does).
std::vector<double> owners_values(SlabTransport& t, const std::vector<double>& mine) {
  Bytes b(mine.size() * sizeof(double));
  std::memcpy(b.data(), mine.data(), b.size());
  std::vector<double> out(mine.size(), 0.0);
  for (auto& part : t.allgather(b)) {
    std::vector<double> theirs(mine.size(), kNaN);
    std::memcpy(theirs.data(), part.data(), std::min(part.size(), b.size()));
    for (std::size_t k = 0; k < out.size(); ++k)
      if (!std::isnan(theirs[k])) out[k] = theirs[k];
  }
  return out;
}

// Sum in id order, so the total is the same however the solid is split between slabs: of records
// (id, N - 1 floats), the N - 1 sums.
template <int N = 4>
std::vector<double> sum_by_id(const std::vector<Bytes>& parts) {
  std::vector<std::array<float, N>> recs;
  for (auto& b : parts)
    for (std::size_t k = 0; k + sizeof(float) * N <= b.size(); k += sizeof(float) * N) {
      std::array<float, N> r;
      std::memcpy(r.data(), b.data() + k, sizeof r);
      recs.push_back(r);
    }
  auto id_of = [](const std::array<float, N>& r) {
    std::uint32_t id;
    std::memcpy(&id, &r[0], sizeof id);
    return id;
  };
  std::sort(recs.begin(), recs.end(), [&](auto& a, auto& b) { return id_of(a) < id_of(b); });
  std::vector<double> f(N - 1, 0.0);
  for (auto& r : recs)
    for (int k = 0; k < N - 1; ++k) f[k] += r[1 + k];
  return f;
}

}  // namespace

std::vector<BodyLoad> body_loads(SlabWorker& w, const RigidBodies& bodies) {
  std::vector<BodyLoad> loads(bodies.size());
  if (bodies.empty()) return loads;
  // The solid particles' sums reach across slab faces: the ghosts must hold their owners' state.
  w.refresh_ghosts();
  for (int b = 0; b < bodies.size(); ++b) {
    const std::uint8_t kind = w.params().materials.solid(bodies.solid(b));
    std::vector<LoadRecord> recs;
    for (const Bytes& part : w.transport().allgather(body_load_records(w, kind, bodies.state(b).centre, bodies.reach(b))))
      for (std::size_t k = 0; k + sizeof(LoadRecord) <= part.size(); k += sizeof(LoadRecord)) {
        LoadRecord r;
        std::memcpy(&r, part.data() + k, sizeof r);
        recs.push_back(r);
      }
    // Summed in id order: the same total however the body is split between slabs.
    std::sort(recs.begin(), recs.end(), [](const LoadRecord& a, const LoadRecord& c) { return a.id < c.id; });
    for (const LoadRecord& r : recs)
      for (int k = 0; k < 3; ++k) loads[b].force[k] += r.v[k], loads[b].torque[k] += r.v[3 + k];
  }
  return loads;
}

std::vector<std::string> probe_columns(const ProbeSpec& p, int dim) {
  const char* axes[3] = {"x", "y", "z"};
  std::vector<std::string> columns;
  auto components = [&](const char* prefix, const char* unit) {
    for (int k = 0; k < dim; ++k) columns.push_back(std::string(prefix) + axes[k] + "[" + unit + "]");
  };
  switch (p.type) {
    case ProbeType::Pressure: columns.push_back("pressure[Pa]"); break;
    case ProbeType::Temperature: columns.push_back("temperature[K]"); break;
    case ProbeType::HeatFlux:
      columns.push_back("q[W/m2]");  // into the fluid
      if (p.length > 0) columns.push_back("nu[-]");
      break;
    case ProbeType::WallPressure:
      // The sensor's reading first (averaged when it has a window), then the instantaneous value.
      columns.push_back("pressure[Pa]");
      if (p.window > 0) columns.push_back("pressure_instant[Pa]");
      break;
    case ProbeType::Velocity: components("v", "m/s"); break;
    case ProbeType::Height: columns.push_back("height[m]"); break;
    case ProbeType::Force:  // 2D: per metre of depth
      components("f", dim == 2 ? "N/m" : "N");
      if (p.viscous)
        for (int k = 0; k < dim; ++k) columns.push_back(std::string("f") + axes[k] + "_viscous[" + (dim == 2 ? "N/m" : "N") + "]");
      break;
    case ProbeType::Front: columns.push_back("front[m]"); break;
    case ProbeType::Body:
      // Centre of mass, angles, velocities, the fluid's force and its torque about the centre of mass.
      components("", "m");
      if (dim == 2) {
        columns.push_back("angle[deg]");
        components("v", "m/s");
        columns.push_back("omega[rad/s]");
        components("f", "N/m");
        columns.push_back("torque[N]");  // N m per metre of depth
      } else {
        components("r", "deg");
        components("v", "m/s");
        components("w", "rad/s");
        components("f", "N");
        components("t", "N m");
      }
      break;
    case ProbeType::Centroid:
      for (int k = 0; k < dim; ++k) columns.push_back(std::string(axes[k]) + "[m]");
      components("v", "m/s");
      break;
    case ProbeType::Drive: components("f", "m/s2"); break;
    case ProbeType::Interface:
      columns.push_back("amplitude[m]");  // half the vertical extent
      columns.push_back("top[m]");
      columns.push_back("bottom[m]");
      break;
  }
  return columns;
}

std::string probe_description(const ProbeSpec& p, int dim) {
  auto point = [&](int n) {
    std::string s = "(";
    for (int k = 0; k < n; ++k) s += fmt::format("{}{:g}", k ? ", " : "", p.position[k]);
    return s + ") m";
  };
  const char* axes[3] = {"x", "y", "z"};
  const std::string of_phase = p.phase >= 0 ? " of " + p.phase_name : "";
  switch (p.type) {
    case ProbeType::Pressure: return "pressure" + of_phase + " at " + point(dim);
    case ProbeType::Temperature: return "temperature" + of_phase + " at " + point(dim);
    case ProbeType::HeatFlux: {
      const std::string face = p.face >= 0 ? fmt::format("face {}{}", axes[p.face / 2], p.face % 2 ? "+" : "-") : "";
      return "heat flux into the fluid through " + (p.solid.empty() ? "the tank's " + face : "solid '" + p.solid + "'" + (face.empty() ? "" : " " + face));
    }
    case ProbeType::WallPressure:
      return fmt::format("wall pressure on a sensor of diameter {:g} mm", 1e3 * p.diameter) + " at " + point(dim) +
             (p.window > 0 ? fmt::format(", {:g} ms mean", 1e3 * p.window) : "");
    case ProbeType::Velocity: return "velocity" + of_phase + " at " + point(dim);
    case ProbeType::Height:
      return (p.phase >= 0 ? p.phase_name : std::string("water")) +
             (dim == 2 ? fmt::format(" height at x = {:g} m", p.position[0]) : " height at (x, y) = " + point(2)) +
             (p.connected ? " (connected column)" : "");
    case ProbeType::Centroid: return "centroid and mean velocity of " + p.phase_name;
    case ProbeType::Drive: return "the body force the drive applies (per unit mass)";
    case ProbeType::Interface: return "interface of " + p.phase_name + ": half its vertical extent, its top and bottom";
    case ProbeType::Force:
      return std::string(p.viscous ? "pressure and viscous force" : "pressure force") + " on solid '" + p.solid + "'" + (p.face >= 0 ? fmt::format(" face {}{}", p.face % 2 ? "+" : "-", axes[p.face / 2]) : "");
    case ProbeType::Body: return "floating solid '" + p.solid + "': centre of mass, angles, velocities, the fluid's force and torque";
    case ProbeType::Front:
      return fmt::format("front{} along {}", of_phase, axes[p.axis]) + (p.min_depth > 0 ? fmt::format(" (water at least {:g} m deep)", p.min_depth) : "");
  }
  return "";
}

std::string probe_header(const ProbeSpec& p, int dim) {
  std::string header = "time[s],step";
  for (auto& c : probe_columns(p, dim)) header += "," + c;
  return header;
}

namespace {

// The rows of an existing probe file up to `step` (whole lines only; a torn last line is dropped),
// or just the header when the file is missing or is not one of ours.
std::string rows_up_to(const std::filesystem::path& path, const std::string& header, std::int64_t step) {
  std::ifstream in(path, std::ios::binary);
  std::string line, kept;
  if (!in || !std::getline(in, line) || line + "\n" != header) return header;
  kept = header;
  while (std::getline(in, line)) {
    if (in.eof()) break;  // no newline after it: a row cut short
    const auto comma = line.find(',');
    if (comma == std::string::npos) continue;
    char* end = nullptr;
    const long long s = std::strtoll(line.c_str() + comma + 1, &end, 10);
    if (end == line.c_str() + comma + 1 || *end != ',' || s > step) continue;
    kept += line + "\n";
  }
  return kept;
}

// The (time, instantaneous pressure) rows of a sensor's CSV up to step `until`, for a restart to
// refill the moving average. A file that cannot be read gives none (the average then restarts).
std::vector<std::pair<double, double>> instant_history(const std::filesystem::path& csv, std::int64_t until) {
  std::vector<std::pair<double, double>> rows;
  std::ifstream in(csv);
  std::string line;
  if (!std::getline(in, line)) return rows;
  int column = -1, k = 0;
  for (std::size_t b = 0; b <= line.size(); ++k) {
    const std::size_t e = std::min(line.find(',', b), line.size());
    if (line.compare(b, e - b, "pressure_instant[Pa]") == 0) column = k;
    b = e + 1;
  }
  if (column < 0) return rows;
  while (std::getline(in, line)) {
    std::vector<double> v;
    for (std::size_t b = 0; b <= line.size();) {
      const std::size_t e = std::min(line.find(',', b), line.size());
      v.push_back(std::strtod(line.c_str() + b, nullptr));
      b = e + 1;
    }
    if (static_cast<int>(v.size()) > column && v[1] <= static_cast<double>(until)) rows.emplace_back(v[0], v[column]);
  }
  return rows;
}

}  // namespace

ProbeSet::ProbeSet(const Case& c, const std::filesystem::path& out_dir, bool writer, std::optional<std::int64_t> resume_step)
    : case_(c) {
  for (auto& spec : c.probes) {
    Probe p{spec, {}, MovingAverage(spec.window)};
    if (spec.type == ProbeType::WallPressure) p.points = sensor_points(spec, c.dim, c.dp);
    probes_.push_back(std::move(p));
  }
  if (!writer || probes_.empty()) return;
  const auto dir = out_dir / "probes";
  create_output_folder(dir);
  for (auto& p : probes_) {
    // Probe names are plain file names (checked by the case loader).
    const auto path = dir / (p.spec.name + ".csv");
    // A sensor with a window refills its moving average from the rows up to the restart step.
    if (resume_step && p.spec.window > 0)
      for (auto [t, v] : instant_history(path, *resume_step)) p.average.add(t, v);
    const std::string header = probe_header(p.spec, c.dim) + "\n";
    write_file_atomically(path, resume_step ? rows_up_to(path, header, *resume_step) : header);
    files_.emplace_back(path, false);
  }
}

std::vector<std::vector<double>> ProbeSet::sample(double time, std::int64_t step, SlabWorker& w, const MotionSet* motions,
                                                  const RigidBodies* bodies) {
  std::vector<std::vector<double>> rows;
  // Near a slab face a probe sums over ghosts: they must hold the same values as their owners.
  w.refresh_ghosts();
  SlabTransport& t = w.transport();
  for (auto& probe : probes_) {
    const ProbeSpec& p = probe.spec;
    std::vector<double> row;
    switch (p.type) {
      case ProbeType::Pressure:
      case ProbeType::Velocity:
      case ProbeType::Height: {
        // Exactly one slab owns the point and has numbers; the others send NaN.
        std::vector<double> mine;
        ProbeSpec at = p;
        std::optional<double> floor;
        const bool floating = p.follow >= 0 && case_.motions[p.follow].floating >= 0;
        if (p.follow >= 0 && (floating ? bodies != nullptr : motions != nullptr)) {  // riding with a moving body
          at.position = floating ? followed_position(p, case_, *bodies) : followed_position(p, case_, *motions, time);
          if (p.type == ProbeType::Height) floor = at.position[case_.dim - 1];
        }
        if (p.type == ProbeType::Velocity) mine = sample_velocity(w, at.position, p.phase);
        else
          mine.push_back(p.type == ProbeType::Pressure ? sample_pressure(w, at.position, p.phase) : sample_height(w, at, case_, floor));
        row = owners_values(t, mine);
        break;
      }
      case ProbeType::WallPressure: {
        // Each point of the disc has one owner; the mean is taken over the points in their order.
        const std::vector<double> at = owners_values(t, sample_wall_pressure(w, probe.points));
        double sum = 0.0;
        for (double v : at) sum += v;
        const double instant = sum / static_cast<double>(at.size());
        if (p.window > 0) row = {probe.average.add(time, instant), instant};
        else row = {instant};
        break;
      }
      case ProbeType::Force: {
        std::uint8_t kind = w.params().materials.solid(0);
        Box box;
        for (std::size_t k = 0; k < case_.solids.size(); ++k)
          if (case_.solids[k].name == p.solid) kind = w.params().materials.solid(static_cast<int>(k)), box = case_.solids[k].box;
        const std::vector<double> sums = sum_by_id<7>(t.allgather(solid_force_records(w, kind, box, p.face, p.viscous)));
        row.assign(sums.begin(), sums.begin() + case_.dim);
        if (p.viscous) row.insert(row.end(), sums.begin() + 3, sums.begin() + 3 + case_.dim);
        break;
      }
      case ProbeType::Temperature: row = owners_values(t, {sample_temperature(w, p.position, p.phase)}); break;
      case ProbeType::HeatFlux: {
        const double q = sum_by_id(t.allgather(heat_flux_records(w, p, case_)))[0] / heat_flux_area(p, case_);
        row.push_back(q);
        if (p.length > 0) row.push_back(q * p.length / (p.conductivity * p.temperature_difference));
        break;
      }
      case ProbeType::Body: {
        int b = 0;
        while (bodies && b < bodies->size() && case_.solids[bodies->solid(b)].name != p.solid) ++b;
        if (!bodies || b == bodies->size()) {
          row.assign(probe_columns(p, case_.dim).size(), kNaN);
          break;
        }
        const BodyState& s = bodies->state(b);
        const BodyLoad& l = bodies->load(b);
        const double kDeg = 180.0 / 3.14159265358979323846;
        const int d = case_.dim;
        auto put = [&](const std::array<double, 3>& v, int from, int n, double scale = 1.0) {
          for (int k = from; k < from + n; ++k) row.push_back(scale * v[k]);
        };
        put(s.centre, 0, d);
        d == 2 ? put(s.angles, 2, 1, kDeg) : put(s.angles, 0, 3, kDeg);
        put(s.velocity, 0, d);
        d == 2 ? put(s.angular_velocity, 2, 1) : put(s.angular_velocity, 0, 3);
        put(l.force, 0, d);
        d == 2 ? put(l.torque, 2, 1) : put(l.torque, 0, 3);
        break;
      }
      case ProbeType::Front: row.push_back(t.max(local_front(w, p.axis, front_level(p, case_), p.phase))); break;
      case ProbeType::Centroid: row = sample_centroid(w, p.phase); break;
      case ProbeType::Drive:
        for (int k = 0; k < case_.dim; ++k) row.push_back(w.params().body_force[k]);
        break;
      case ProbeType::Interface: {
        const auto [low, high] = local_interface_extent(w, case_, p.phase);
        const double bottom = -t.max(-low), top = t.max(high);
        if (top >= bottom) row = {0.5 * (top - bottom), top, bottom};
        else row = {kNaN, kNaN, kNaN};
        break;
      }
    }
    rows.push_back(row);
  }
  for (std::size_t k = 0; k < files_.size(); ++k) {
    std::ostringstream row;
    row.precision(9);
    row << time << ',' << step;
    for (double v : rows[k]) row << ',' << v;
    row << '\n';
    files_[k].append(row.str());
  }
  return rows;
}

}  // namespace spate
