#pragma once
// Sub-particle-scale (SPS) turbulence: the Smagorinsky closure of Dalrymple & Rogers (2006,
// Coastal Eng. 53:141, eqs. 12-16), the large-eddy model of the leading open-source SPH code
// (`turbulence: {model: sps}`). The filtered (Favre-averaged) momentum equation gains the
// divergence of the SPS stress tensor tau, whose kinematic form is
//   tau_ab / rho = 2 nu_t S_ab - (2/3) nu_t S_kk delta_ab - (2/3) C_I Delta^2 |S|^2 delta_ab,
//   nu_t = (C_s Delta)^2 |S|,   |S| = sqrt(2 S_ab S_ab),   S_ab = (dv_a/dx_b + dv_b/dx_a) / 2,
// C_s = 0.12 (Smagorinsky), C_I = 0.0066 (Blin et al.'s isotropic coefficient), Delta = dp (the
// filter width is the particle spacing). In SPH, with T = tau / rho (the kinematic stress over the
// density, per particle),
//   (1/rho grad . (rho tau/rho))_i = sum_j m_j (T_i + T_j) . grad_i W_ij,
// the symmetric form of the pressure term (eq. 7 with -p I replaced by the stress), which conserves
// momentum pair by pair.
//
// Two passes over the neighbours (backend/particle_updates.hpp) after the fluid pass, with a halo
// refresh of T in between (sim/slab_worker.cpp: the first needs the ghost walls' no-slip velocities,
// which arrive with the fluid pass's refresh): (1) the velocity gradient of each owned fluid
// particle, sum_j V_j (v_j - v_i) (x) grad_i W_ij, over fluid neighbours (any fluid) and walls (at
// the no-slip velocity the wall pass extrapolates: the shear the wall imposes; a free-slip face
// mirrors only the normal velocity and imposes none), and T from it; (2) the divergence, added to
// the acceleration of the fluid pass. A wall neighbour carries i's own T (the stress continued
// into the wall, as Adami's walls continue the pressure): a uniform stress then exerts no net force
// on a particle next to a wall (zero-order consistency), and the wall takes the fluid's stress.
//
// Laminar flows: a resolved laminar flow (|S| dp^2 << nu) changes by (C_s dp)^2 |S| / nu, 4e-6 of
// the viscous stress in the shipped Poiseuille channel. The eddy viscosity does not limit the time step: with |S| below U / dp,
// 0.125 h^2 / nu_t exceeds 14 dp / U, far above the acoustic limit h / c0.
#include "fluid_interactions.hpp"
#include "velocity_gradient.hpp"

namespace spate {

// The symmetric kinematic stress over density, T = tau / rho, of one particle: the diagonal
// (xx, yy[, zz]) and the shear (xy in 2D; xy, xz, yz in 3D), as the registry stores them
// (`sps_stress`, `sps_shear`).
template <int Dim>
struct SpsStress {
  Vec<Dim> diagonal = zero_vec<Dim>();
  float shear[3] = {0.0f, 0.0f, 0.0f};
  // T_ab for a != b: index of the pair (a, b) in `shear`.
  SPATE_HD static int shear_index(int a, int b) { return a + b - 1; }  // (0,1) 0, (0,2) 1, (1,2) 2
  SPATE_HD float at(int a, int b) const { return a == b ? diagonal[a] : shear[shear_index(a, b)]; }
};

// The mass a neighbour of material m_j brings to fluid particle i's SPS sums: its own for a fluid,
// i's for a wall, which stands in for i's fluid (as in the fluid pass).
SPATE_HD float sps_neighbour_mass(const PhysicsParams& P, std::uint8_t m_j, float mass_i) {
  return P.is_fluid(m_j) ? P.materials.of(m_j).mass : mass_i;
}

// Stores particle i's T and eddy viscosity (the fields `sps_stress`, `sps_shear`,
// `eddy_viscosity`); load_sps_stress (backend/particle_updates.hpp) reads T back.
template <int Dim, class Fields>
SPATE_HD void store_sps_stress(Fields& f, std::uint32_t i, const SpsStress<Dim>& T, float nu_t) {
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) f.sps_stress[k][i] = T.diagonal[k];
  SPATE_UNROLL for (int k = 0; k < Dim * (Dim - 1) / 2; ++k) f.sps_shear[k][i] = T.shear[k];
  f.eddy_viscosity[i] = nu_t;
}

// T = tau / rho_i of the closure above, and the eddy viscosity nu_t [m^2/s] (exported).
template <int Dim>
SPATE_HD SpsStress<Dim> sps_stress(const PhysicsParams& P, const VelocityGradient<Dim>& s, float rho_i, float& eddy_viscosity) {
  float S[Dim][Dim];
  float S2 = 0.0f, trace = 0.0f;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    SPATE_UNROLL for (int b = 0; b < Dim; ++b) {
      S[a][b] = 0.5f * (s.g[a][b] + s.g[b][a]);
      S2 += 2.0f * S[a][b] * S[a][b];
    }
    trace += S[a][a];
  }
  const float nu_t = P.turbulence.smagorinsky2 * sqrtf(S2);
  eddy_viscosity = nu_t;
  const float isotropic = -(2.0f / 3.0f) * nu_t * trace - P.turbulence.isotropic * S2;
  const float inv_rho = 1.0f / rho_i;
  SpsStress<Dim> T;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    T.diagonal[a] = (2.0f * nu_t * S[a][a] + isotropic) * inv_rho;
    SPATE_UNROLL for (int b = a + 1; b < Dim; ++b) T.shear[SpsStress<Dim>::shear_index(a, b)] = 2.0f * nu_t * S[a][b] * inv_rho;
  }
  return T;
}

// Neighbour j's term of fluid particle i's SPS acceleration: m_j (T_i + T_j) . grad_i W_ij
// (branch-free: beyond the support F = 0).
template <class Kernel, int Dim>
SPATE_HD Vec<Dim> sps_pair_term(const PhysicsParams& P, const Vec<Dim>& xi, const SpsStress<Dim>& Ti, const Vec<Dim>& xj,
                                const SpsStress<Dim>& Tj, float mass_j) {
  const Vec<Dim> r = xi - xj;
  const float mF = mass_j * kernel_gradient_factor<Kernel>(P, dot(r, r));
  Vec<Dim> acc = zero_vec<Dim>();
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    SPATE_UNROLL for (int b = 0; b < Dim; ++b) acc[a] += mF * (Ti.at(a, b) + Tj.at(a, b)) * r[b];
  }
  return acc;
}

// The same for a neighbour inside the support, zero beyond it.
template <class Kernel, int Dim>
SPATE_HD Vec<Dim> sps_pair_acceleration(const PhysicsParams& P, const Vec<Dim>& xi, const SpsStress<Dim>& Ti, const Vec<Dim>& xj,
                                        const SpsStress<Dim>& Tj, float mass_j) {
  const Vec<Dim> r = xi - xj;
  if (dot(r, r) >= P.support2) return zero_vec<Dim>();  // as the CPU backend selects neighbours
  return sps_pair_term<Kernel, Dim>(P, xi, Ti, xj, Tj, mass_j);
}

}  // namespace spate
