#pragma once
// Heat transfer (docs/physics.md, "Heat transfer"): conduction through fluids and walls, thermal
// conditions on the tank's faces, and Boussinesq buoyancy. Written once for both backends; the
// passes that call it are backend/particle_updates.hpp's update_wall_temperature and
// update_heat_rates, which run only when the case has a `heat:` section (HeatParams::on).
//
// Conduction in the form of Cleary & Monaghan (1999), after Brookshaw (1985):
//   rho_i c_i dT_i/dt = sum_j V_j k_ij (T_i - T_j) (r_ij . grad_i W_ij) / (r_ij^2 + eta^2),
//   k_ij = 4 k_i k_j / (k_i + k_j)   (twice the harmonic mean)
// The harmonic mean keeps the heat flux continuous across a jump of k between materials (a
// conjugate interface, two fluids); the sum is antisymmetric in i and j for the energy
// V_i rho_i c_i T_i, so heat is conserved pair by pair. V_j is m_j / rho_j for a fluid, dp^dim for a
// wall particle; rho c is the fluid's current density times its c_p, a wall's own density times its
// c_p. The kernel factor is normalised on the start lattice, eta^2 included (lattice_gradient_moment
// of kernels.hpp with eta2), so that the operator is exact for a quadratic temperature on the undisturbed lattice, as the
// gradient is exact for a linear field (kernels.hpp).
//
// Walls. A wall particle either conducts (ThermalCondition::Conducting: the tank or a solid with its
// own k, c_p and density, integrated like a fluid: conjugate heat transfer), is held at a fixed
// temperature (a solid that is a heat source or sink; it exchanges heat with its own k, or the
// fluid's when it has none), or stands behind a tank face that takes a condition. Such a particle
// stands in for the
// fluid mirrored across the face (as Adami's wall velocity does for no-slip): it holds the
// temperature that puts the face at the imposed temperature (or passes the imposed flux, or none)
// given the fluid's temperature at its mirror point, and it conducts with the k of the material it
// mirrors. The
// line runs through the temperature of the particle nearest the mirror point, carried along the
// face to the point by the gradient of a linear least-squares fit over the neighbours of that
// particle's material (so that a wall under an interface between two materials mirrors each side
// with its own slope), at that particle's own distance from the face (face_wall_temperature):
// exact for a linear temperature on any particle distribution; limited to the range of the
// neighbours' temperatures
// (mirror_temperature). Shepard or fitted means instead smooth the temperature over
// the kernel (a sinusoid 40 dp long along an adiabatic wall then decays 4% too fast in a tank 10 dp
// deep); a uniform "wall at T_w" is off by about dp/L of the difference; a wall that does not conduct
// (for an adiabatic face) slows the conduction along it, its neighbours missing half their support
// (the same sinusoid 5% too slow).
//
// Buoyancy (Boussinesq): a fluid with expansion coefficient beta feels -beta (T - T_ref) g; its
// equation of state and rest density do not change (docs/physics.md says why). g is the case's
// gravity unless heat.gravity says otherwise (a closed, full tank may leave gravity out of the
// momentum equation and keep it for the buoyancy alone: the Boussinesq equations in the departure
// from the hydrostatic pressure, with a sound speed that need not carry the hydrostatic head).
//
// Temperature-dependent viscosity: a fluid's `thermal.viscosity` table, mu(T) piecewise linear
// between its points and held at the end values beyond them (a cooling melt thickens). Each pair
// then takes the harmonic mean of its two particles' viscosities (the multiphase pair terms'
// eq. 8, which every run with a table uses).
#include <cstdint>

#include "host_device.hpp"
#include "kernels.hpp"
#include "materials.hpp"
#include "vec.hpp"

namespace spate {

constexpr int kMaxThermalEntries = 16;

// How a particle's temperature is found.
enum class ThermalCondition : std::uint8_t {
  Conducting,  // integrated from the conduction rate (every fluid; walls and solids with their own k)
  Fixed,       // held at its starting temperature (a solid at a fixed temperature)
  // Tank faces only: the wall temperature pass sets the particles behind the face each step.
  FaceTemperature,  // the face at a fixed temperature [K]
  FaceFlux,         // a fixed heat flux into the fluid through the face [W/m^2]
  Adiabatic,        // no heat through the face
};

constexpr int kMaxViscosityTables = 4;
constexpr int kMaxViscosityPoints = 8;

// mu(T) of one fluid: `points` pairs, temperatures ascending.
struct ViscosityTable {
  int points = 0;
  float temperature[kMaxViscosityPoints] = {};  // [K]
  float viscosity[kMaxViscosityPoints] = {};    // [Pa s]
};

// Piecewise linear between the points; beyond them, the end values.
SPATE_HD float table_viscosity(const ViscosityTable& t, float T) {
  if (!(T > t.temperature[0])) return t.viscosity[0];
  for (int k = 1; k < t.points; ++k)
    if (T < t.temperature[k]) {
      const float s = (T - t.temperature[k - 1]) / (t.temperature[k] - t.temperature[k - 1]);
      return t.viscosity[k - 1] + s * (t.viscosity[k] - t.viscosity[k - 1]);
    }
  return t.viscosity[t.points - 1];
}

struct ThermalMaterial {
  float conductivity = 0.0f;   // k [W/(m K)]
  float specific_heat = 0.0f;  // c_p [J/(kg K)]
  float density = 0.0f;        // walls and solids: their density [kg/m^3] (a fluid uses its particles')
  float expansion = 0.0f;      // fluids: beta [1/K] (Boussinesq)
  float reference_temperature = 0.0f;  // fluids: T_ref of the buoyancy [K]
  ThermalCondition condition = ThermalCondition::Conducting;
};

struct FaceCondition {
  ThermalCondition kind = ThermalCondition::Adiabatic;  // Conducting: the tank's own material
  float value = 0.0f;  // FaceTemperature: [K]; FaceFlux: into the fluid [W/m^2]
};

struct HeatParams {
  bool on = false;
  bool walls_conduct = false;   // the tank or a solid conducts (its own k > 0, integrated)
  // The Laplacian's lattice normalisation over the gradient's: lattice_gradient_moment(...) over
  // lattice_gradient_moment(..., eta2) (kernels.hpp; conduction_term).
  float laplacian_scale = 0.0f;
  float wall_volume = 0.0f;     // dp^dim
  float gravity[3] = {0.0f, 0.0f, 0.0f};  // of the buoyancy (heat.gravity; default the case's)
  std::uint8_t of[kMaxMaterials] = {};  // material -> entry (fluids, the tank, each solid)
  ThermalMaterial entry[kMaxThermalEntries];
  FaceCondition face[6];  // the tank's faces, 2 axis + side (0 lower, 1 upper)
  // Temperature-dependent viscosity: fluid m follows table viscosity_table_of[m] - 1 (0: none).
  bool viscosity_varies = false;
  std::uint8_t viscosity_table_of[kMaxFluids] = {};
  ViscosityTable viscosity_table[kMaxViscosityTables];

  SPATE_HD const ThermalMaterial& material(std::uint8_t m) const { return entry[of[m]]; }
  // The viscosity of fluid m at temperature t (`mu`, its constant viscosity, without a table).
  SPATE_HD float viscosity(std::uint8_t m, float mu, float t) const {
    const int k = m < kMaxFluids ? viscosity_table_of[m] : 0;
    return k > 0 ? table_viscosity(viscosity_table[k - 1], t) : mu;
  }
  // The largest viscosity fluid m reaches (its table's largest value), for the viscous time step.
  float largest_viscosity(std::uint8_t m, float mu) const {
    const int k = m < kMaxFluids ? viscosity_table_of[m] : 0;
    if (k == 0) return mu;
    float most = 0.0f;
    for (int p = 0; p < viscosity_table[k - 1].points; ++p) most = fmaxf(most, viscosity_table[k - 1].viscosity[p]);
    return most;
  }
};

// The tank face a tank wall particle at x stands behind: the first axis along which it lies outside
// the fluid region [lo, hi] (in a corner: the lower axis, so that an x face owns its corners), its
// depth behind the face and the sign of the way into the fluid. axis -1: not behind a face.
struct ThermalFace {
  int axis = -1;
  int side = 0;      // 0: the lower face, 1: the upper
  float depth = 0.0f;
  float into_fluid = 0.0f;
  SPATE_HD int index() const { return 2 * axis + side; }
};

SPATE_HD ThermalFace thermal_face(const float (&lo)[3], const float (&hi)[3], const float* x, int dim) {
  ThermalFace f;
  for (int k = 0; k < dim; ++k) {
    if (x[k] < lo[k]) return ThermalFace{k, 0, lo[k] - x[k], 1.0f};
    if (x[k] > hi[k]) return ThermalFace{k, 1, x[k] - hi[k], -1.0f};
  }
  return f;
}

// Distance of x into the fluid from face f's plane (negative behind it).
SPATE_HD float distance_from_face(const float (&lo)[3], const float (&hi)[3], const ThermalFace& f, const float* x) {
  return f.side == 0 ? x[f.axis] - lo[f.axis] : hi[f.axis] - x[f.axis];
}

// How the temperature of particle x of material m is found, given `tank` (the tank's material) and
// the tank's fluid region: a fluid's and a conducting wall's is integrated (Conducting), a fixed
// solid's held (Fixed); behind a tank face, the face's condition (`face` says which face).
SPATE_HD ThermalCondition temperature_condition(const HeatParams& H, std::uint8_t m, std::uint8_t tank, const float (&lo)[3],
                                                const float (&hi)[3], const float* x, int dim, ThermalFace& face) {
  face = ThermalFace{};
  if (m != tank) return H.material(m).condition;
  face = thermal_face(lo, hi, x, dim);
  return face.axis < 0 ? H.material(m).condition : H.face[face.index()].kind;
}

// k_ij = 4 k_i k_j / (k_i + k_j), 0 when both are 0 (an adiabatic pair).
SPATE_HD float pair_conductivity(float ki, float kj) {
  const float sum = ki + kj;
  return sum > 0.0f ? 4.0f * ki * kj / sum : 0.0f;
}

// One neighbour's share of rho_i c_i dT_i/dt [W/m^3]: V_j k_ij (T_i - T_j) F_lap r^2 / (r^2 + eta^2),
// from the radial factors the fluid pair terms compute for the same pair (PairKinematics): r^2, the
// gradient factor F (grad_i W = F r, with the gradient's lattice normalisation) and 1/(r^2 + eta^2).
// The Laplacian's normalisation is the gradient's times H.laplacian_scale (the kernels' gradient
// factors are linear in the normalisation), so that the CPU computes the square root, the kernel
// and the reciprocal once per pair for both. Branch-free, so that the CPU's pair loop vectorises:
// beyond the support F is exactly 0 (kernels.hpp), and so is the term.
SPATE_HD float conduction_term(const HeatParams& H, float r2, float F, float inv_r2_eta, float ti, float tj, float kij, float vj) {
  return vj * kij * (ti - tj) * (H.laplacian_scale * F) * (r2 * inv_r2_eta);
}

// The volume a neighbour conducts with: a fluid's m / rho (as m times 1/rho, the fluid pair terms'
// volume), a wall's or solid's dp^dim (HeatParams::wall_volume, passed by value so that the CPU's
// pair loop reads it outside the loop: a load under the select does not vectorise).
SPATE_HD float heat_volume(bool fluid, float mass, float rho, float wall_volume) {
  return fluid ? mass * (1.0f / rho) : wall_volume;
}

// Boussinesq acceleration of a fluid particle at temperature t: -beta (t - T_ref) g.
template <int Dim>
SPATE_HD Vec<Dim> buoyancy_acceleration(const ThermalMaterial& m, const float (&gravity)[3], float t) {
  Vec<Dim> a;
  const float s = -m.expansion * (t - m.reference_temperature);
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) a[k] = s * gravity[k];
  return a;
}

// The linear least-squares fit of the temperature around a wall particle behind a face, from the
// particles of one material that carry their own temperature: sums of the weights w = V_j W_ij and
// of w dx, w dx dx^T, w T, w T dx with dx = (x_j - x_w) / h (scaled, so that the moments are O(1)).
// w dx dx^T is symmetric: its upper triangle only, row by row (wxx[pair_index(a, b)], a <= b).
template <int Dim>
struct LinearFitSums {
  static constexpr int kPairs = Dim * (Dim + 1) / 2;
  // The place of w dx_a dx_b (a <= b) in wxx.
  SPATE_HD static constexpr int pair_index(int a, int b) { return a * Dim - a * (a - 1) / 2 + (b - a); }
  float w = 0.0f, wt = 0.0f;
  float wx[Dim] = {}, wtx[Dim] = {};
  float wxx[kPairs] = {};
  float lowest = INFINITY, highest = -INFINITY;  // the neighbours' temperatures span [lowest, highest]
  SPATE_HD float moment(int a, int b) const { return a <= b ? wxx[pair_index(a, b)] : wxx[pair_index(b, a)]; }
  // The terms one neighbour adds (weight vw = V_j W_ij, temperature t, offset dx), numbered in the
  // order w, wt, wx, wtx, wxx: emit(k, term k). The one formula of add() and of the CPU's vectorised
  // lanes (FitLanes, cpu/fluid_pass.hpp), which keep each term in an array of its own.
  static constexpr int kTerms = 2 + 2 * Dim + kPairs;
  template <class Offset, class Emit>
  SPATE_HD static void terms(float vw, float t, const Offset& dx, Emit&& emit) {
    emit(0, vw);
    emit(1, vw * t);
    SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
      emit(2 + a, vw * dx[a]);
      emit(2 + Dim + a, vw * t * dx[a]);
      SPATE_UNROLL for (int b = a; b < Dim; ++b) emit(2 + 2 * Dim + pair_index(a, b), vw * dx[a] * dx[b]);
    }
  }
  // Term k's sum (k a constant once the loops above are unrolled).
  SPATE_HD float& term(int k) {
    return k == 0 ? w : k == 1 ? wt : k < 2 + Dim ? wx[k - 2] : k < 2 + 2 * Dim ? wtx[k - 2 - Dim] : wxx[k - 2 - 2 * Dim];
  }
  SPATE_HD void add(float vw, const Vec<Dim>& dx, float t) {
    lowest = t < lowest ? t : lowest;
    highest = t > highest ? t : highest;
    terms(vw, t, dx, [&](int k, float v) { term(k) += v; });
  }
  // Another partial fit's sums added to these (lanes added in lane order: pair_lanes.hpp).
  SPATE_HD void merge(const LinearFitSums& x) {
    lowest = x.lowest < lowest ? x.lowest : lowest;
    highest = x.highest > highest ? x.highest : highest;
    w += x.w;
    wt += x.wt;
    SPATE_UNROLL for (int a = 0; a < Dim; ++a) wx[a] += x.wx[a], wtx[a] += x.wtx[a];
    SPATE_UNROLL for (int q = 0; q < kPairs; ++q) wxx[q] += x.wxx[q];
  }
};

// The mirror temperature: t_near (the temperature of the neighbour nearest the mirror point) carried
// by the fitted gradient g over the scaled offset `to_mirror`, limited to the neighbours' range. The
// limit keeps a poorly conditioned fit (few neighbours, nearly in a line: a wall's deepest layer
// beside a disordered layer of fluid) from throwing the wall's temperature far off; a smooth field's
// mirror value lies within its neighbours' range but for a sliver of curvature.
template <int Dim>
SPATE_HD float mirror_temperature(const LinearFitSums<Dim>& s, float t_near, const Vec<Dim>& g, const Vec<Dim>& to_mirror) {
  const float t = t_near + dot(g, to_mirror);
  return t < s.lowest ? s.lowest : t > s.highest ? s.highest : t;
}

// The gradient g (per scaled unit, dx / h) of the fit T = c + g . dx from the normal equations
// [w, wx^T; wx, wxx] [c; g] = [wt; wtx] (Gaussian elimination with partial pivoting); zero when the
// neighbours do not span the space (a pivot below 1e-4 w: all of them on one line).
template <int Dim>
SPATE_HD Vec<Dim> fitted_gradient(const LinearFitSums<Dim>& s) {
  constexpr int N = Dim + 1;
  float m[N][N + 1];
  m[0][0] = s.w;
  m[0][N] = s.wt;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    m[0][1 + a] = m[1 + a][0] = s.wx[a];
    m[1 + a][N] = s.wtx[a];
    SPATE_UNROLL for (int b = 0; b < Dim; ++b) m[1 + a][1 + b] = s.moment(a, b);
  }
  for (int col = 0; col < N; ++col) {
    int pivot = col;
    for (int r = col + 1; r < N; ++r)
      if (fabsf(m[r][col]) > fabsf(m[pivot][col])) pivot = r;
    if (!(fabsf(m[pivot][col]) > 1.0e-4f * s.w)) return zero_vec<Dim>();
    if (pivot != col)
      for (int k = 0; k <= N; ++k) {
        const float t = m[col][k];
        m[col][k] = m[pivot][k];
        m[pivot][k] = t;
      }
    for (int r = col + 1; r < N; ++r) {
      const float f = m[r][col] / m[col][col];
      for (int k = col; k <= N; ++k) m[r][k] -= f * m[col][k];
    }
  }
  float x[N];
  for (int r = N - 1; r >= 0; --r) {
    float v = m[r][N];
    for (int k = r + 1; k < N; ++k) v -= m[r][k] * x[k];
    x[r] = v / m[r][r];
  }
  Vec<Dim> g;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) g[a] = x[1 + a];
  return g;
}

// The temperature of a wall particle `depth` behind a face with condition c, on the straight line
// through the temperature t_near of a particle `near_depth` in front of the face (the fluid nearest
// the wall particle's mirror point, carried along the face to it), with conductivity k there: the
// face at c.value (T_w = c.value - (t_near - c.value) depth / near_depth), the flux c.value into the
// fluid (k (T_w - t_near) / (depth + near_depth) = q), or none (adiabatic: t_near). A line through
// the particle itself rather than through the mirror point keeps a deep wall layer right where its
// mirror point lies beyond its neighbours (they are then one row of fluid along the face, which
// fixes no gradient across it: the deeper layer took the first row's temperature, and a face with a
// heat flux passed 3.7% too much, docs/studies/heated-cavity.md).
SPATE_HD float face_wall_temperature(const FaceCondition& c, float t_near, float near_depth, float k, float depth) {
  switch (c.kind) {
    case ThermalCondition::FaceTemperature: return c.value - (t_near - c.value) * depth / near_depth;
    case ThermalCondition::FaceFlux: return k > 0.0f ? t_near + c.value * (depth + near_depth) / k : t_near;
    default: return t_near;
  }
}

// The stable step of explicit conduction: dt <= factor h^2 / alpha, alpha = k / (rho c_p) the
// largest diffusivity among the case's materials (Cleary & Monaghan 1999 use 0.1). `rho` is each
// entry's density (a fluid's rest density for fluids).
inline float conduction_time_step(const ThermalMaterial& m, float rho, float h, float factor) {
  const float rc = rho * m.specific_heat;
  if (!(m.conductivity > 0.0f) || !(rc > 0.0f)) return INFINITY;
  return factor * h * h * rc / m.conductivity;
}

}  // namespace spate
