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
};

template <int Dim>
struct FluidRates {
  Vec<Dim> acc = zero_vec<Dim>();
  float density_rate = 0.0f;
};

// Density diffusion between two particles of fluid M (delta-SPH, Molteni & Colagrossi 2009), times
// `factor` (1 for a neighbour of the same fluid, 0 otherwise); r_ji . grad_i W = -r2 F. The
// Fourtakas et al. (2019) variant first subtracts the hydrostatic part rho^H_ji = rho0 g.r_ji / c^2
// over one pair distance, with c^2 = dp/drho of eq. 9 at the pair's mean density,
// c0^2 (rho/rho0)^(gamma - 1), not c0^2: at depth the Tait hydrostatic density gradient is a few
// percent below the linear one, and diffusing towards the linear profile biases deep pressures
// upward. Switches are factors, not branches, so the loop stays vectorisable.
template <bool Gamma7, int Dim>
SPATE_HD float density_diffusion(const PhysicsParams& P, const FluidMaterial& M, float factor, float rho_i, float rho_j,
                                 const Vec<Dim>& r, float r2, float F, float inv_r2_eta, float volume_j) {
  const float diffusion = (P.diffusion == DensityDiffusion::None ? 0.0f : 1.0f) * (P.delta * P.h * M.c0 * 2.0f);
  const float hydrostatic = (P.diffusion == DensityDiffusion::Fourtakas ? 1.0f : 0.0f) * (M.rho0 / (M.c0 * M.c0));
  float g_dot_rji = 0.0f;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) g_dot_rji -= P.gravity[k] * r[k];
  const float s = 0.5f * (rho_i + rho_j) / M.rho0;
  const float drho_ji = (rho_j - rho_i) - hydrostatic * g_dot_rji / tait_sound_speed_ratio2<Gamma7>(s, M.gamma);
  return factor * diffusion * drho_ji * (-r2 * F) * inv_r2_eta * volume_j;
}

// What every pair term needs of the pair's geometry and motion: r_ij, its square, the kernel
// gradient factor (grad_i W_ij = F r_ij), 1/(r^2 + eta^2), and the relative velocity, once as the
// laminar term sees a wall (its extrapolated no-slip velocity) and once as continuity and artificial
// viscosity see it (static walls: their real, zero velocity; Adami et al. 2012), with vr its
// projection on r_ij.
template <int Dim>
struct PairKinematics {
  Vec<Dim> r;
  float r2, F, inv_r2_eta;
  Vec<Dim> v_ij_wall, v_ij_visc;
  float vr;
};

template <class Kernel, int Dim>
SPATE_HD PairKinematics<Dim> pair_kinematics(const PhysicsParams& P, const ParticleState<Dim>& i, const ParticleState<Dim>& j,
                                             float j_fluid) {
  PairKinematics<Dim> k;
  k.r = i.x - j.x;
  k.r2 = dot(k.r, k.r);
  k.F = Kernel::gradient_factor(sqrtf(k.r2) * P.inv_h, P.gradient_norm, P.inv_h2);
  k.inv_r2_eta = 1.0f / (k.r2 + P.eta2);
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    k.v_ij_visc[a] = i.v[a] - j.v[a];
    k.v_ij_wall[a] = i.v[a] - j_fluid * j.v[a];
  }
  k.vr = dot(k.v_ij_wall, k.r);
  return k;
}

// The contribution of neighbour j to fluid particle i of material M. Branch-free, so that the CPU
// driver's inner loop vectorises: beyond the support the kernel gradient is exactly 0, and for
// j = i the offset r is 0, so every term vanishes by itself and adds +0 to the sums (which leaves
// them unchanged). Gamma7: M.gamma == 7 (the exact product instead of pow, chosen per run).
template <class Kernel, int Dim, bool Gamma7 = true>
SPATE_HD FluidRates<Dim> fluid_pair_terms(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                          const ParticleState<Dim>& j) {
  const float j_fluid = P.is_fluid(j.material) ? 1.0f : 0.0f;
  const PairKinematics<Dim> pk = pair_kinematics<Kernel, Dim>(P, i, j, j_fluid);
  const Vec<Dim>& r = pk.r;
  const float r2 = pk.r2, F = pk.F, inv_r2_eta = pk.inv_r2_eta, vr = pk.vr;
  const Vec<Dim>& v_ij_visc = pk.v_ij_visc;
  const float inv_rho_i = 1.0f / i.rho;
  const float inv_rho_j = 1.0f / j.rho;
  const float volume_i = M.mass * inv_rho_i;
  const float volume_j = M.mass * inv_rho_j;

  // Eq. 6 (normalised continuity; the same as d rho/dt = rho_i sum V_j v_ij . grad W).
  float drho = i.rho * volume_j * vr * F;
  drho += density_diffusion<Gamma7>(P, M, j_fluid, i.rho, j.rho, r, r2, F, inv_r2_eta, volume_j);

  // Eq. 7, pressure force, and Monaghan (1992) artificial viscosity for approaching pairs (vr < 0;
  // alpha = 0 switches it off).
  const float mu_ij = P.h * (vr < 0.0f ? vr : 0.0f) * inv_r2_eta;
  const float pi_ij = -P.artificial_viscosity * M.c0 * mu_ij / (0.5f * (i.rho + j.rho));
  const float radial = -M.mass * ((i.p + j.p) * inv_rho_i * inv_rho_j + pi_ij) * F;
  // Eq. 8, inter-particle-averaged viscosity of Hu & Adams (2006): 2 mu_i mu_j / (mu_i + mu_j) = mu
  // for one fluid. The paper prints 4 mu_i mu_j / (mu_i + mu_j), twice the Hu & Adams (and Morris
  // 1997) value; with it the Poiseuille test settles at half the analytic velocity (docs/physics.md).
  const float laminar = M.viscosity / M.mass * (volume_i * volume_i + volume_j * volume_j) * (r2 * F) * inv_r2_eta;

  FluidRates<Dim> out;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) out.acc[k] = radial * r[k] + laminar * v_ij_visc[k];
  out.density_rate = drho;
  return out;
}

template <class Kernel, int Dim, bool Gamma7>
SPATE_HD void accumulate_fluid_pair(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                    const ParticleState<Dim>& j, FluidRates<Dim>& out) {
  const FluidRates<Dim> t = fluid_pair_terms<Kernel, Dim, Gamma7>(P, M, i, j);
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) out.acc[k] += t.acc[k];
  out.density_rate += t.density_rate;
}

// Body forces added once per fluid particle after the pair sum.
template <int Dim>
SPATE_HD void add_body_forces(const PhysicsParams& P, FluidRates<Dim>& out) {
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) out.acc[k] += P.gravity[k] + P.body_force[k];
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
