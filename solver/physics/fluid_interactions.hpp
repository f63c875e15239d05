#pragma once
// The pair interaction of a fluid particle i with a neighbour j (fluid or wall): density rate
// (continuity, eq. 6, plus density diffusion) and acceleration (pressure, eq. 7; laminar viscosity,
// eq. 8; optional Monaghan artificial viscosity). Written once; the CPU and CUDA drivers only loop.
// Fluid properties come from i's material (materials.hpp); with one fluid they are j's too (a
// wall neighbour stands in for the fluid it bounds). Several fluids: multiphase_interactions.hpp.
#include <cstdint>

#include "eos.hpp"
#include "params.hpp"
#include "vec.hpp"

namespace spate {

template <int Dim>
struct ParticleState {
  Vec<Dim> x;    // position
  Vec<Dim> v;    // velocity (for walls: the no-slip velocity extrapolated by the wall pass)
  float rho;     // density
  float p;       // pressure
  std::uint8_t material;  // index into PhysicsParams::materials (materials.hpp)
  // With moving or free-slip walls only (the MovingWalls pair terms): the velocity continuity sees,
  // a fluid's own, a wall's prescribed rigid motion (boundary_velocity()); and the one the
  // artificial viscosity sees, the same except along a free-slip face (sliding_velocity()).
  Vec<Dim> w;
  Vec<Dim> w_av;
};

// What continuity and artificial viscosity see of neighbour j: a fluid's velocity, a wall's
// prescribed velocity (its `v` holds the no-slip velocity the viscous term sees).
template <int Dim>
SPATE_HD Vec<Dim> boundary_velocity(const PhysicsParams& P, const ParticleState<Dim>& j) {
  return P.is_fluid(j.material) ? j.v : wall_velocity<Dim>(P, j.material, j.x);
}

// What the artificial viscosity sees of neighbour j (PairKinematics::vr_av), given j.w: j.w, but
// a free-slip face slides with the fluid: along it the wall's velocity is the tangential part of
// j.v (the fluid's, apply_free_slip), across it j.w's, so the term damps the approach and is no
// friction: u = j.v - ((j.v - j.w) . n) n. The face's normal is j's frame (params.hpp WallFrame: a
// box tank's face, or a shaped wall's own normal). Once per neighbour, not per pair, so that the
// pair terms stay free of the face test. `f`, `j`: the fields and index j's state was loaded from.
template <int Dim>
SPATE_HD Vec<Dim> sliding_velocity(const WallFrame<Dim>& face, const ParticleState<Dim>& sj) {
  if (face.shear != FaceShear::FreeSlip) return sj.w;
  const float vn = dot(sj.v - sj.w, face.n);
  Vec<Dim> u;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) u[a] = sj.v[a] - vn * face.n[a];
  return u;
}
template <int Dim, class Fields>
SPATE_HD Vec<Dim> sliding_velocity(const PhysicsParams& P, const Fields& f, std::uint32_t j, const ParticleState<Dim>& sj) {
  if (!P.free_slip_axes && !P.materials.faces_slide) return sj.w;  // moving walls alone: nothing slides
  if (P.is_fluid(sj.material)) return sj.w;
  return sliding_velocity<Dim>(wall_frame<Dim>(P, f, j, sj.x), sj);
}

// Monaghan's alpha for a pair: alpha between fluid particles, alpha times the wall factor
// (fluid.wall_artificial_viscosity) against a wall (j_fluid = 0). A no-slip wall at rest makes the
// term a friction as well as a damping of approach: for i sliding along the wall the pair direction
// to a wall particle diagonally ahead makes v_ij . r_ij < 0. At H/60-H/120 that friction slows the
// bottom centimetres of a dam-break surge by a third (docs/studies/impact-pressures.md, "What
// keeps p3 low"). A free-slip wall does not rub: the term sees it slide with the fluid
// (PairKinematics::vr_av).
SPATE_HD float artificial_alpha(const PhysicsParams& P, float j_fluid) {
  return P.artificial_viscosity * (j_fluid + (1.0f - j_fluid) * P.wall_artificial_viscosity);
}

template <int Dim>
struct FluidRates {
  Vec<Dim> acc = zero_vec<Dim>();
  float density_rate = 0.0f;
  // Over wall neighbours, for the Riemann solver's wall term (finish_fluid_rates):
  // sum V_j grad_i W_ij (points from i into the wall) and sum V_j dW/dr (< 0).
  Vec<Dim> wall_gradient = zero_vec<Dim>();
  float wall_weight = 0.0f;
};

// Density diffusion between two particles of fluid M (delta-SPH, Molteni & Colagrossi 2009), times
// `factor` (1 for a neighbour of the same fluid, 0 otherwise); r_ji . grad_i W = -r2 F, g_dot_rji =
// g . r_ji (PairKinematics). The Fourtakas et al. (2019) variant first subtracts the hydrostatic
// part rho^H_ji = rho0 g.r_ji / c^2 over one pair distance, with c^2 = dp/drho of eq. 9 at the
// pair's mean density, c0^2 (rho/rho0)^(gamma - 1), not c0^2: at depth the Tait hydrostatic density
// gradient is a few percent below the linear one, and diffusing towards the linear profile biases
// deep pressures upward. Not with `density.diffusion: riemann` (riemann_pair_terms instead).
// Switches are factors, not branches, so the loop stays vectorisable. Not with `antuono` either:
// its pass adds the diffusion after the fluid pass (density_gradient.hpp).
//
// The diffusion flux itself, delta h c0 psi_ij r_ji . grad_i W_ij / (r^2 + eta^2) V_j with the
// pair's half jump psi_ij / 2 = drho_ji, times `factor`; every variant's jump goes through it.
SPATE_HD float diffusion_flux(const PhysicsParams& P, const FluidMaterial& M, float factor, float drho_ji, float r2, float F,
                              float inv_r2_eta, float volume_j) {
  return factor * (P.delta * P.h * M.c0 * 2.0f) * drho_ji * (-r2 * F) * inv_r2_eta * volume_j;
}

template <bool Gamma7>
SPATE_HD float density_diffusion(const PhysicsParams& P, const FluidMaterial& M, float factor, float rho_i, float rho_j,
                                 float g_dot_rji, float r2, float F, float inv_r2_eta, float volume_j) {
  const bool delta_sph = P.diffusion == DensityDiffusion::MolteniColagrossi || P.diffusion == DensityDiffusion::Fourtakas;
  const float hydrostatic = (P.diffusion == DensityDiffusion::Fourtakas ? 1.0f : 0.0f) * (M.rho0 / (M.c0 * M.c0));
  const float s = 0.5f * (rho_i + rho_j) / M.rho0;
  const float drho_ji = (rho_j - rho_i) - hydrostatic * g_dot_rji / tait_sound_speed_ratio2<Gamma7>(s, M.gamma);
  return diffusion_flux(P, M, factor * option_factor(delta_sph), drho_ji, r2, F, inv_r2_eta, volume_j);
}

// What every pair term needs of the pair's geometry and motion: r_ij, its square, the kernel
// gradient factor (grad_i W_ij = F r_ij), 1/(r^2 + eta^2), g . r_ji (the hydrostatic jump's
// direction, for density diffusion and the Riemann solver), and the relative velocity, once as the
// laminar term sees a wall (its extrapolated no-slip velocity) and once as continuity and artificial
// viscosity see it (a wall's real velocity: zero for static walls, the prescribed motion j.w for
// moving ones; Adami et al. 2012), with vr its projection on r_ij. vr_av: the projection the
// artificial viscosity takes, vr but against a free-slip tank face, which slides with the fluid:
// there the wall's tangential components are the fluid's (j.v, apply_free_slip), so the term damps
// the approach and is no friction. Continuity keeps the wall's real velocity (with the sliding
// wall in continuity too, a particle of the Lobovsky surge fell through a free-slip floor).
template <int Dim>
struct PairKinematics {
  Vec<Dim> r;
  float r2, r_len, F, inv_r2_eta, g_dot_rji;
  Vec<Dim> v_ij_wall, v_ij_visc;
  float vr, vr_av;
};

// The radial part, all that the positions give: r = x_i - x_j, r^2, |r|, F (grad_i W = F r) and
// 1/(r^2 + eta^2), shared by the fluid pair terms and heat transfer's conduction term.
template <class Kernel, int Dim>
SPATE_HD PairKinematics<Dim> radial_kinematics(const PhysicsParams& P, const Vec<Dim>& xi, const Vec<Dim>& xj) {
  PairKinematics<Dim> k;  // the rest is pair_kinematics's
  k.r = xi - xj;
  k.r2 = dot(k.r, k.r);
  k.r_len = sqrtf(k.r2);
  k.F = Kernel::gradient_factor(k.r_len * P.inv_h, P.gradient_norm, P.inv_h2);
  k.inv_r2_eta = 1.0f / (k.r2 + P.eta2);
  return k;
}

template <class Kernel, int Dim, bool MovingWalls = false>
SPATE_HD PairKinematics<Dim> pair_kinematics(const PhysicsParams& P, const ParticleState<Dim>& i, const ParticleState<Dim>& j,
                                             float j_fluid) {
  PairKinematics<Dim> k = radial_kinematics<Kernel, Dim>(P, i.x, j.x);
  k.g_dot_rji = 0.0f;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) k.g_dot_rji -= P.gravity[a] * k.r[a];
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    k.v_ij_visc[a] = i.v[a] - j.v[a];
    if constexpr (MovingWalls) k.v_ij_wall[a] = i.v[a] - j.w[a];
    else k.v_ij_wall[a] = i.v[a] - j_fluid * j.v[a];
  }
  k.vr = dot(k.v_ij_wall, k.r);
  k.vr_av = k.vr;
  // Free-slip faces: only runs with moving or free-slip walls take this loop (walls_have_velocity);
  // j.w_av is sliding_velocity(), which is j.w off a free-slip face (then vr_av = vr exactly).
  if constexpr (MovingWalls) k.vr_av = dot(i.v - j.w_av, k.r);
  return k;
}
template <class Kernel, int Dim, bool MovingWalls = false>
SPATE_HD PairKinematics<Dim> pair_kinematics(const PhysicsParams& P, const ParticleState<Dim>& i, const ParticleState<Dim>& j) {
  return pair_kinematics<Kernel, Dim, MovingWalls>(P, i, j, P.is_fluid(j.material) ? 1.0f : 0.0f);
}

// The linearised (acoustic) Riemann problem between i (left) and j (right) along the line from i
// to j (Zhang, Hu & Adams 2017, J. Comput. Phys. 335:605; SPHinXsys), with rho c = rho0 c0:
//   U* = (U_L + U_R)/2 + (p_i - p_j) / (2 rho0 c0),   p* = (p_i + p_j)/2 + rho0 beta (U_L - U_R) / 2,
// U_L - U_R = -(v_ij . r_ij)/|r_ij| (> 0 when the pair approaches). In the continuity equation
// U* adds rho_i sum V_j (p_i - p_j)/(rho0 c0) dW/dr, a pressure diffusion; the hydrostatic jump
// rho0 g . r_ij is taken out of p_i - p_j first (as Fourtakas et al. do for delta-SPH) so still
// water stays still at a free surface, where the sum is one-sided. Walls: none, as SPHinXsys,
// whose wall state is exactly that hydrostatic jump. In the momentum equation p_i + p_j becomes
// 2 p*: beta = min(eta max(U_L - U_R, 0), c0) is the low-dissipation limiter (eta = 3), which
// leaves expansion and slow compression alone and damps an impact like the full Riemann solver.
// Walls: see finish_fluid_rates. Both terms assume one rho0 c0 on both sides, so they act between
// particles of fluid M only: `factor` is 1 for a neighbour of i's fluid, 0 otherwise (walls, and
// with several fluids a neighbour of another fluid, whose interface pressure multiphase_pair_terms
// already takes from the acoustic Riemann problem with both impedances).
struct RiemannPairTerms {
  float density_rate;   // the pressure diffusion, added to d rho_i/dt
  float p_dissipation;  // 2 p* - (p_i + p_j), added to p_i + p_j in eq. 7
};

template <int Dim>
SPATE_HD RiemannPairTerms riemann_pair_terms(const PhysicsParams& P, const FluidMaterial& M, float factor, const ParticleState<Dim>& i,
                                             const ParticleState<Dim>& j, const PairKinematics<Dim>& pk, float volume_j) {
  const float riemann_diffusion = option_factor(P.diffusion == DensityDiffusion::Riemann);
  const float dp_dynamic = (i.p - j.p) + M.rho0 * pk.g_dot_rji;
  RiemannPairTerms out;
  out.density_rate = factor * riemann_diffusion * i.rho * volume_j * dp_dynamic / (M.rho0 * M.c0) * pk.F * pk.r_len;
  const float riemann_flux = option_factor(P.flux == MomentumFlux::Riemann);
  const float jump = -pk.vr * factor / (pk.r_len + 1e-6f * P.h);
  const float compression = jump > 0.0f ? jump : 0.0f;
  const float beta = P.riemann_limiter * compression < M.c0 ? P.riemann_limiter * compression : M.c0;
  out.p_dissipation = riemann_flux * M.rho0 * beta * compression;
  return out;
}

// A pair's rates from its radial (times r_ij) and laminar (times v_ij) accelerations and its
// density rate, with the wall sums of the Riemann wall term (finish_fluid_rates) when j is a wall
// (j_fluid = 0): V_j grad_i W_ij and V_j dW/dr. WallSums false: those are zero (no Riemann option).
template <int Dim, bool WallSums = true>
SPATE_HD FluidRates<Dim> pair_rates(const PairKinematics<Dim>& pk, float radial, float laminar, float drho, float j_fluid,
                                    float volume_j) {
  FluidRates<Dim> out;
  const float wall_volume = WallSums ? (1.0f - j_fluid) * volume_j * pk.F : 0.0f;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
    out.acc[k] = radial * pk.r[k] + laminar * pk.v_ij_visc[k];
    out.wall_gradient[k] = wall_volume * pk.r[k];
  }
  out.density_rate = drho;
  out.wall_weight = wall_volume * pk.r_len;
  return out;
}

// The contribution of neighbour j to fluid particle i of material M. Branch-free, so that the CPU
// driver's inner loop vectorises: beyond the support the kernel gradient is exactly 0, and for
// j = i the offset r is 0, so every term vanishes by itself and adds +0 to the sums (which leaves
// them unchanged). Gamma7: M.gamma == 7 (the exact product instead of pow, chosen per run).
// MovingWalls: some walls move (j.w holds what continuity sees of j) or slide (free-slip faces,
// vr_av); without it walls are at rest.
// Riemann: the Riemann options' terms (riemann_pair_terms and the wall sums); without it they are
// left out, which gives the same result when neither option is on (they would add exactly zero).
// pk: the pair's kinematics (pair_kinematics), which a caller that also needs them passes in.
template <class Kernel, int Dim, bool Gamma7 = true, bool MovingWalls = false, bool Riemann = true>
SPATE_HD FluidRates<Dim> fluid_pair_terms(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                          const ParticleState<Dim>& j, const PairKinematics<Dim>& pk) {
  const float j_fluid = P.is_fluid(j.material) ? 1.0f : 0.0f;
  const float r2 = pk.r2, F = pk.F, inv_r2_eta = pk.inv_r2_eta, vr = pk.vr, vr_av = pk.vr_av;
  const float inv_rho_i = 1.0f / i.rho;
  const float inv_rho_j = 1.0f / j.rho;
  const float volume_i = M.mass * inv_rho_i;
  const float volume_j = M.mass * inv_rho_j;

  // Eq. 6 (normalised continuity; the same as d rho/dt = rho_i sum V_j v_ij . grad W), density
  // diffusion and the Riemann solver's pressure diffusion between fluid particles.
  float drho = i.rho * volume_j * vr * F;
  drho += density_diffusion<Gamma7>(P, M, j_fluid, i.rho, j.rho, pk.g_dot_rji, r2, F, inv_r2_eta, volume_j);
  RiemannPairTerms riemann{0.0f, 0.0f};
  if constexpr (Riemann) {
    riemann = riemann_pair_terms<Dim>(P, M, j_fluid, i, j, pk, volume_j);
    drho += riemann.density_rate;
  }

  // Eq. 7, pressure force, and Monaghan (1992) artificial viscosity for approaching pairs (vr < 0;
  // alpha = 0 switches it off; against a wall alpha times the wall factor, artificial_alpha).
  const float mu_ij = P.h * (vr_av < 0.0f ? vr_av : 0.0f) * inv_r2_eta;
  const float pi_ij = -artificial_alpha(P, j_fluid) * M.c0 * mu_ij / (0.5f * (i.rho + j.rho));
  const float p_sum = Riemann ? i.p + j.p + riemann.p_dissipation : i.p + j.p;
  const float radial = -M.mass * (p_sum * inv_rho_i * inv_rho_j + pi_ij) * F;
  // Eq. 8, inter-particle-averaged viscosity of Hu & Adams (2006): 2 mu_i mu_j / (mu_i + mu_j) = mu
  // for one fluid. The paper prints 4 mu_i mu_j / (mu_i + mu_j), twice the Hu & Adams (and Morris
  // 1997) value; with it the Poiseuille test settles at half the analytic velocity (docs/physics.md).
  const float laminar = M.viscosity / M.mass * (volume_i * volume_i + volume_j * volume_j) * (r2 * F) * inv_r2_eta;

  return pair_rates<Dim, Riemann>(pk, radial, laminar, drho, j_fluid, volume_j);
}
template <class Kernel, int Dim, bool Gamma7 = true, bool MovingWalls = false, bool Riemann = true>
SPATE_HD FluidRates<Dim> fluid_pair_terms(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                          const ParticleState<Dim>& j) {
  return fluid_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, i, j, pair_kinematics<Kernel, Dim, MovingWalls>(P, i, j));
}

template <int Dim>
SPATE_HD void add_pair_rates(FluidRates<Dim>& out, const FluidRates<Dim>& t) {
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
    out.acc[k] += t.acc[k];
    out.wall_gradient[k] += t.wall_gradient[k];
  }
  out.density_rate += t.density_rate;
  out.wall_weight += t.wall_weight;
}

template <class Kernel, int Dim, bool Gamma7, bool MovingWalls, bool Riemann = true>
SPATE_HD void accumulate_fluid_pair(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                    const ParticleState<Dim>& j, FluidRates<Dim>& out) {
  add_pair_rates(out, fluid_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, i, j));
}

// A relaxation zone (PhysicsParams::zone, case key `relaxation_zone`): inside its box the fluid's
// velocity relaxes towards the zone's (a plane Poiseuille profile across the box's height when
// parabolic) with the time constant 1/inv_time, a forcing zone as in wave flumes' relaxation
// zones: upstream of a body in a periodic channel it gives the body the inflow of a channel with
// an inlet (its own wake, which would come round the period, is reset there).
template <int Dim>
SPATE_HD void relax_in_zone(const PhysicsParams& P, const ParticleState<Dim>& i, Vec<Dim>& acc) {
  const auto& z = P.zone;
  bool inside = true;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) inside = inside && i.x[a] >= z.lo[a] && i.x[a] <= z.hi[a];
  if (!inside) return;
  float scale = 1.0f;
  if (z.parabolic) {
    const float s = (i.x[Dim - 1] - z.lo[Dim - 1]) / (z.hi[Dim - 1] - z.lo[Dim - 1]);
    scale = 4.0f * s * (1.0f - s);
  }
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) acc[a] += (scale * z.velocity[a] - i.v[a]) * z.inv_time;
}

// Once per fluid particle after the pair sum: the Riemann solver's wall term, then body forces
// and the relaxation zone.
// Against a wall the Riemann problem is between the fluid and its mirror image (velocity 2 v_w - v_i,
// v_w = 0), along the wall's normal n: the jump is 2 v_i . n towards the wall, and p* - (p_i + p_w)/2
// acts along n (SPHinXsys). n is not stored for walls: the kernel-weighted direction from the walls to
// i, -sum V_j grad_i W_ij, is the wall normal seen from i (diagonal in a corner). Sliding along a
// wall is then not a compression (the pair direction r_ij would make it one, i.e. friction).
template <int Dim>
SPATE_HD void finish_fluid_rates(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i, FluidRates<Dim>& out) {
  const float g2 = dot(out.wall_gradient, out.wall_gradient);
  if (P.flux == MomentumFlux::Riemann && g2 > 0.0f) {
    const float inv_g = -1.0f / sqrtf(g2);
    float v_n = 0.0f;
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) v_n += i.v[k] * out.wall_gradient[k] * inv_g;
    const float compression = v_n < 0.0f ? -2.0f * v_n : 0.0f;
    const float beta = P.riemann_limiter * compression < M.c0 ? P.riemann_limiter * compression : M.c0;
    // -(p_dissipation / rho_i) sum V_j dW/dr along n (away from the wall).
    const float push = -M.rho0 * beta * compression / i.rho * out.wall_weight;
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) out.acc[k] += push * out.wall_gradient[k] * inv_g;
  }
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) out.acc[k] += P.gravity[k] + P.body_force[k];
  if (P.zone.inv_time > 0.0f) relax_in_zone(P, i, out.acc);
}

// Mass summation, eq. 5 (times rho0): rho_i = sum_j m_j W_ij, self included by the caller's loop
// (m_j: the mass of i's fluid, which walls stand in for).
template <class Kernel, int Dim>
SPATE_HD float summation_density_term(const PhysicsParams& P, const FluidMaterial& M, const Vec<Dim>& xi, const Vec<Dim>& xj) {
  const Vec<Dim> r = xi - xj;
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return 0.0f;
  return M.mass * Kernel::value(sqrtf(r2) * P.inv_h, P.kernel_norm);
}

}  // namespace spate
