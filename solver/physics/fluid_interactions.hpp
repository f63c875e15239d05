#pragma once
// The pair interaction of a fluid particle i with a neighbour j (fluid or wall): density rate
// (continuity, eq. 6, plus density diffusion) and acceleration (pressure, eq. 7; laminar viscosity,
// eq. 8; optional Monaghan artificial viscosity). Written once; the CPU and CUDA drivers only loop.
#include <cstdint>

#include "params.hpp"
#include "vec.hpp"

namespace spate {

template <int Dim>
struct ParticleState {
  Vec<Dim> x;    // position
  Vec<Dim> v;    // velocity (for walls: the no-slip velocity extrapolated by the wall pass)
  float rho;     // density
  float p;       // pressure
  std::uint8_t kind;
};

template <int Dim>
struct FluidRates {
  Vec<Dim> acc = zero_vec<Dim>();
  float density_rate = 0.0f;
};

template <class Kernel, int Dim>
SPATE_HD void accumulate_fluid_pair(const PhysicsParams& P, const ParticleState<Dim>& i,
                                    const ParticleState<Dim>& j, FluidRates<Dim>& out) {
  const Vec<Dim> r = i.x - j.x;  // r_ij
  const float r2 = dot(r, r);
  if (r2 >= P.support2 || r2 == 0.0f) return;  // outside the support, or i itself
  const float q = sqrtf(r2) * P.inv_h;
  const float F = Kernel::gradient_factor(q, P.gradient_norm, P.inv_h2);  // grad_i W_ij = F r_ij
  const bool j_fluid = is_fluid(j.kind);
  const float volume_i = P.mass / i.rho;
  const float volume_j = P.mass / j.rho;
  const float r2_eta = r2 + P.eta2;

  // Walls are static: continuity and artificial viscosity see their real (zero) velocity, the
  // laminar term their extrapolated no-slip velocity (Adami et al. 2012).
  const Vec<Dim> v_ij_wall = j_fluid ? i.v - j.v : i.v;
  const Vec<Dim> v_ij_visc = i.v - j.v;
  const float vr = dot(v_ij_wall, r);

  // Eq. 6 (normalised continuity; the same as d rho/dt = rho_i sum V_j v_ij . grad W).
  float drho = i.rho * volume_j * vr * F;
  // Density diffusion between fluid particles (delta-SPH). r_ji . grad_i W = -r2 F.
  if (P.diffusion != DensityDiffusion::None && j_fluid) {
    float drho_ji = j.rho - i.rho;
    if (P.diffusion == DensityDiffusion::Fourtakas) {
      // Subtract the hydrostatic part (Fourtakas et al. 2019): rho^H_ji = rho0 g.r_ji / c^2 over one
      // pair distance. c^2 = dp/drho of eq. 9 at the pair's mean density, c0^2 (rho/rho0)^6, not
      // c0^2: at depth the Tait hydrostatic density gradient is a few percent below the linear one,
      // and diffusing towards the linear profile biases deep pressures upward.
      float g_dot_rji = 0.0f;
      for (int k = 0; k < Dim; ++k) g_dot_rji -= P.gravity[k] * r[k];
      const float s = 0.5f * (i.rho + j.rho) / P.rho0;
      const float s2 = s * s;
      drho_ji -= P.rho0 * g_dot_rji / (P.c0 * P.c0 * s2 * s2 * s2);
    }
    drho += P.delta * P.h * P.c0 * 2.0f * drho_ji * (-r2 * F) / r2_eta * volume_j;
  }

  // Eq. 7, pressure force.
  float radial = -P.mass * (i.p + j.p) / (i.rho * j.rho) * F;
  // Monaghan (1992) artificial viscosity, only for approaching pairs.
  if (P.artificial_viscosity > 0.0f && vr < 0.0f) {
    const float mu_ij = P.h * vr / r2_eta;
    const float pi_ij = -P.artificial_viscosity * P.c0 * mu_ij / (0.5f * (i.rho + j.rho));
    radial += -P.mass * pi_ij * F;
  }
  // Eq. 8, inter-particle-averaged viscosity of Hu & Adams (2006): 2 mu_i mu_j / (mu_i + mu_j) = mu
  // for one fluid. The paper prints 4 mu_i mu_j / (mu_i + mu_j), twice the Hu & Adams (and Morris
  // 1997) value; with it the Poiseuille test settles at half the analytic velocity (docs/physics.md).
  const float laminar = P.viscosity / P.mass * (volume_i * volume_i + volume_j * volume_j) * (r2 * F) / r2_eta;

  for (int k = 0; k < Dim; ++k) out.acc[k] += radial * r[k] + laminar * v_ij_visc[k];
  out.density_rate += drho;
}

// Body forces added once per fluid particle after the pair sum.
template <int Dim>
SPATE_HD void add_body_forces(const PhysicsParams& P, FluidRates<Dim>& out) {
  for (int k = 0; k < Dim; ++k) out.acc[k] += P.gravity[k] + P.body_force[k];
}

// Mass summation, eq. 5 (times rho0): rho_i = sum_j m_j W_ij, self included by the caller's loop.
template <class Kernel, int Dim>
SPATE_HD float summation_density_term(const PhysicsParams& P, const Vec<Dim>& xi, const Vec<Dim>& xj) {
  const Vec<Dim> r = xi - xj;
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return 0.0f;
  return P.mass * Kernel::value(sqrtf(r2) * P.inv_h, P.kernel_norm);
}

}  // namespace spate
