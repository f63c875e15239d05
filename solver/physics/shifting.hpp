#pragma once
// Particle shifting of the delta-plus-SPH model (Sun, Colagrossi, Marrone & Zhang 2017, Comput.
// Methods Appl. Mech. Engrg. 315:25, eq. 13-14; Sun et al. 2019, Comput. Methods Appl. Mech. Engrg.
// 348:912): after each step every fluid particle moves, on top of its Lagrangian motion, by
//   dr_i = -C CFL Ma (2h)^2 sum_j [1 + R (W_ij / W(dp))^n] grad_i W_ij V_j,   R = 0.2, n = 4,
// from where particles crowd towards where they are sparse, which keeps the particle distribution
// regular through an impact (no voids, no clumps, hence no spurious pressure noise). CFL Ma is the
// paper's dt U / h with U = Ma c0 the flow's reference speed (Ma = `shifting.mach`, 0.1 for the
// usual c0 = 10 U), so dr_i = -4 C h U dt sum_j (...). The R term (the tensile-instability
// correction) repels particles closer than dp. The displacement is capped at `kMaxShiftFraction` dp
// per step, a safeguard only: in the bulk dr is a small fraction of that.
// R is P.shifting.tensile (0.2; the relaxation before t = 0, sim/relax.hpp, takes 0, so that it
// settles where sum_j V_j grad W_ij vanishes: where eq. 7's pressure term exerts no force).
// Free surface (Sun et al. 2017, eq. 14, with the divergence of position of Lind et al. 2012,
// J. Comput. Phys. 231:1499, in place of the eigenvalue of the renormalisation matrix):
//   s_i = -(1/Dim) sum_j V_j r_ij . grad_i W_ij  is 1 inside the fluid (exactly, with the lattice
//   gradient renormalisation) and drops where the kernel is cut by the free surface (about 0.5 on
//   it). Walls count as neighbours (a wall is not a free surface).
//   s_i < splash:                 isolated or splashed particle: no shifting;
//   splash <= s_i < vicinity:     the free surface and the row under it (s = 0.64 and 0.96 on a
//                                 lattice under a flat surface; 1 from the second row on): the
//                                 component of dr_i along the outward normal n_i = -sum V_j grad W
//                                 / |.| is removed when it points out of the fluid (n . dr > 0);
//   otherwise:                    dr_i unchanged.
// Several fluids (Lind et al.'s free-surface rule applied at an interface, as multiphase shifting
// schemes do; cf. Mokos, Rogers & Stansby 2017, J. Hydraul. Res. 55:143): next to particles of
// another fluid the component of dr_i along the interface normal
// n_i = sum_{j of another fluid} V_j grad W_ij / |.| is removed, so particles slide along the
// interface and never across it (a shift across it would mix the fluids, or squeeze one into the
// other).
// As in the 2017 model the shift is not an ALE transport: by default the velocity is not corrected
// for it. With `shifting.correct_velocity: true` (ShiftingParams::correct_velocity) the velocity
// follows the particle to its shifted position to first order, as the temperature always does and
// as Xu, Stansby & Laurence (2009, J. Comput. Phys. 228:6703) and Lind et al. (2012) correct every
// hydrodynamic variable:  v_i += (grad v)_i dr_i,  with
//   (grad v)_i = sum_j V_j (v_j - v_i) (x) grad_i W_ij,   V_j = m / rho0,
// summed in the shifting pass's own neighbour loop (walls give their no-slip velocity, the one the
// viscous term sees). Without it a particle shifted across a shear layer carries its velocity into
// the neighbouring stream: in the cylinder's wake that is a momentum diffusion of its own.
// The density follows it with `shifting.volume_consistent: true` (ShiftingParams::volume_consistent;
// continuity density only): a particle keeps its mass, so where the shift spreads particles (a clump
// evened out, a void filled) their volumes grow and their densities fall, and where it gathers them
// the reverse. Eq. 6 with the displacements in place of the velocities gives the change, applied
// once per step after the neighbours' shifts have reached the ghosts (a halo refresh of `shift`):
//   delta rho_i = rho_i sum_j V_j (dr_i - dr_j) . grad_i W_ij,   V_j = m / rho0 (as above),
// which is, to O(rho / rho0 - 1), the change of the summation density sum_j m W_ij under the
// displacements: the continuity density stays the density of the particles' arrangement. It is
// the shift's divergence in the continuity equation, -rho div(dr); not an ALE form in which mass
// moves between particles with the shift (to first order -rho div u + dr . grad rho per unit time,
// the density of a point carried through the field), which spate's fixed masses do not follow.
// Without the term a shifted particle keeps its density wherever it goes: where shifting works
// without pause (the fluid in tension behind a cylinder) the mean density then climbs step after
// step, and the pressure with it (docs/studies/cylinder-flow.md: 1002 -> 1011 kg/m^3 over 3 s).
// Off by default: every shipped free-surface case was validated without it (and without it the
// shifting perturbs the pressure: docs/studies/impact-pressures.md measures it).
#include <cstdint>

#include "fluid_interactions.hpp"
#include "kernels.hpp"
#include "params.hpp"
#include "vec.hpp"
#include "velocity_gradient.hpp"

namespace spate {

constexpr float kMaxShiftFraction = 0.25f;   // cap of |dr| per step, in dp
constexpr float kSurfaceSplash = 0.4f;       // s_i below: no shifting
constexpr float kSurfaceVicinity = 0.975f;    // s_i below: the normal component is removed

template <int Dim>
struct ShiftingSums {
  Vec<Dim> concentration = zero_vec<Dim>();  // sum V_j [1 + R (W_ij / W(dp))^4] grad_i W_ij
  Vec<Dim> gradient = zero_vec<Dim>();       // sum V_j grad_i W_ij (points into the fluid)
  float divergence = 0.0f;                   // -sum V_j r_ij . grad_i W_ij (Dim inside the fluid)
  Vec<Dim> interface = zero_vec<Dim>();      // sum V_j grad_i W_ij over fluids other than i's
};

// Neighbour j (fluid or wall) of fluid particle i of material M (index material_i); w_dp = W(dp). Adds exactly 0 for
// j = i and beyond the support. Every neighbour takes the volume m / rho0 (the wall lattice's, and
// the fluid's at rest): with V_j = m / rho_j (the paper's) a compressed fluid next to a wall, whose
// Adami density is a pressure boundary condition and not a packing, is drawn into the wall; in the
// hydrostatic tank that variant lost 7% of the bottom pressure instead of 3%
// (docs/studies/impact-pressures.md).
template <class Kernel, int Dim>
SPATE_HD void accumulate_shifting_pair(const PhysicsParams& P, const FluidMaterial& M, std::uint8_t material_i, float w_dp,
                                       const Vec<Dim>& xi, const ParticleState<Dim>& j, ShiftingSums<Dim>& s) {
  const Vec<Dim> r = xi - j.x;
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return;
  const float q = sqrtf(r2) * P.inv_h;
  const float F = Kernel::gradient_factor(q, P.gradient_norm, P.inv_h2);
  const float volume = M.mass / M.rho0;
  const float ratio = Kernel::value(q, P.kernel_norm) / w_dp;
  const float ratio2 = ratio * ratio;
  const float weight = volume * F;
  const float tensile = 1.0f + P.shifting.tensile * ratio2 * ratio2;
  const float other = P.is_fluid(j.material) && j.material != material_i ? weight : 0.0f;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
    s.concentration[k] += tensile * weight * r[k];
    s.gradient[k] += weight * r[k];
    s.interface[k] += other * r[k];
  }
  s.divergence -= weight * r2;
}

// The displacement of fluid particle i from its sums, for a step dt (see the top of the file).
template <int Dim>
SPATE_HD Vec<Dim> shifting_displacement(const PhysicsParams& P, const FluidMaterial& M, const ShiftingSums<Dim>& s, float dt) {
  Vec<Dim> dr = zero_vec<Dim>();
  // Without a free surface (shifting.free_surface: false) a cut kernel is a void in the fluid, which
  // the shift fills instead of keeping it as a surface.
  const bool free_surface = P.shifting.free_surface;
  const float surface = s.divergence / static_cast<float>(Dim);
  if (free_surface && surface < kSurfaceSplash) return dr;
  const float scale = -4.0f * P.shifting.coefficient * P.h * P.shifting.mach * M.c0 * dt;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) dr[k] = scale * s.concentration[k];
  const float g2 = dot(s.gradient, s.gradient);
  if (free_surface && surface < kSurfaceVicinity && g2 > 0.0f) {
    // n = -gradient / |gradient| (outward); remove n (n . dr) when n . dr > 0.
    const float inv_g = 1.0f / sqrtf(g2);
    const float outward = -dot(s.gradient, dr) * inv_g;
    if (outward > 0.0f) SPATE_UNROLL for (int k = 0; k < Dim; ++k) dr[k] += outward * s.gradient[k] * inv_g;
  }
  const float i2 = dot(s.interface, s.interface);
  if (i2 > 0.0f) {
    // Along the interface only: remove n (n . dr), n = interface / |interface|.
    const float along_n = dot(s.interface, dr) / i2;
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) dr[k] -= along_n * s.interface[k];
  }
  const float limit = kMaxShiftFraction * P.dp;
  const float len2 = dot(dr, dr);
  if (len2 > limit * limit) {
    const float f = limit / sqrtf(len2);
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) dr[k] *= f;
  }
  return dr;
}

// `shifting.correct_velocity`: the velocity's change at the shifted position, (dr . grad) v, from
// the velocity gradient's sums (velocity_gradient.hpp, g[a][b] = d v_b / d x_a).
template <int Dim>
SPATE_HD Vec<Dim> shift_velocity_change(const VelocityGradient<Dim>& grad, const Vec<Dim>& dr) {
  Vec<Dim> dv = zero_vec<Dim>();
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) SPATE_UNROLL for (int b = 0; b < Dim; ++b) dv[b] += dr[a] * grad.g[a][b];
  return dv;
}

// The volume-consistent density's pair part (see the top of the file): V_j (dr_i - dr_j) .
// grad_i W_ij for neighbour j (fluid or wall; a wall's dr is 0) at xj with displacement dr_j, V_j =
// m / rho0 of fluid particle i's material M. Exactly 0 for j = i and beyond the support; the sum
// times rho_i is the density change (shift_density_change).
template <class Kernel, int Dim>
SPATE_HD float shift_volume_term(const PhysicsParams& P, const FluidMaterial& M, const Vec<Dim>& xi, const Vec<Dim>& dri,
                                     const Vec<Dim>& xj, const Vec<Dim>& drj) {
  const Vec<Dim> r = xi - xj;
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return 0.0f;
  return M.mass / M.rho0 * kernel_gradient_factor<Kernel>(P, r2) * dot(dri - drj, r);
}

// delta rho_i of fluid particle i (density rho_i) from its pair sum.
SPATE_HD float shift_density_change(float rho_i, float pair_sum) { return rho_i * pair_sum; }

}  // namespace spate
