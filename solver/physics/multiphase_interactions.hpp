#pragma once
// The pair interaction of fluid particle i with neighbour j when the case has several fluids
// (phases): the same terms as fluid_interactions.hpp (continuity, density diffusion, pressure,
// artificial and laminar viscosity), each written so that it stays consistent across an interface
// between fluids of very different rest densities (up to water and air, 1000:1). Chosen at
// dispatch (dispatch_pair_loop, Multiphase = fluids > 1), so a one-fluid run never executes a line
// of it. Why this form and not another: docs/physics.md, "Several fluids".
//
//  - Continuity, eq. 6 of the paper in its normalised form with each particle's own rho0:
//      d(rho/rho0)_i/dt = (rho_i/rho0_i) sum_j (m_j/rho_j) v_ij . grad W_ij,
//    stored as rho_i: the neighbour enters through its volume m_j/rho_j (about dp^dim in every
//    phase), never its density, so a water particle next to air sees no density jump.
//    Between particles of two fluids, j's velocity becomes the velocity of the interface of the
//    pair's acoustic Riemann problem, v* = (Z_i v_i + Z_j v_j)/(Z_i + Z_j) (Rezavand, Zhang & Hu
//    2020, without its pressure-difference term), and v_j - v_i becomes 2 (v* - v_i):
//      d(rho/rho0)_i/dt += (rho_i/rho0_i) V_j [2 Z_j/(Z_i + Z_j)] v_ij . grad W_ij.
//    Equal impedances give eq. 6 itself. Across water and air the interface moves with the water:
//    a water particle's density no longer follows the compression of the (soft) air around it,
//    which otherwise rings the water's pressure by +-15 kPa at a dam-break front, while an air
//    particle meets the water as a wall moving with it.
//  - Pressure, eq. 7 with the neighbour's own mass, -(1/rho_i) sum_j V_j (p_i + p_j) grad W_ij
//    (Colagrossi & Landrini 2003), where p_i + p_j becomes twice the interface pressure of the
//    linearised (acoustic) Riemann problem between the two particles,
//      p*_ij = (Z_j p_i + Z_i p_j) / (Z_i + Z_j),   Z = rho c,
//    i.e. Hu & Adams' (2006) density-weighted inter-particle pressure with each phase's sound
//    speed. Equal impedances (one fluid, or a wall) give (p_i + p_j)/2, eq. 7 itself; across water
//    and air the air's pressure governs, so that pressure noise of the water does not kick the
//    light phase. Antisymmetric in i, j (V_i V_j p*_ij), so momentum is conserved. This is the
//    interface pressure a Riemann-solver scheme (Rezavand et al. 2020) starts from.
//    With momentum.pressure_gradient `difference`, 2 p*_ij - 2 p_i = 2 Z_i (p_j - p_i)/(Z_i + Z_j)
//    instead: zero for a uniform pressure on any arrangement of particles. The symmetric form's
//    sum_j V_j (p_i + p_j) grad W_ij holds 2 p_i sum_j V_j grad W_ij, which vanishes only on the
//    start lattice: under the absolute pressure (background plus hydrostatic, about 2-4 in the
//    Rayleigh-Taylor case) the lattice resists being sheared like an elastic solid, with a
//    stiffness that dwarfs the pressure differences (rho_h - rho_l) g a that drive a small
//    interface wave. It held the Rayleigh-Taylor instability to a fraction of its linear growth
//    (docs/studies/rayleigh-taylor.md). The price: pairs no longer conserve momentum exactly, and
//    nothing in the pressure term keeps particles from clumping (no cure for the tensile instability).
//  - Laminar viscosity, eq. 8 with the harmonic mean 2 mu_i mu_j / (mu_i + mu_j) of the two
//    phases' viscosities (Hu & Adams 2006), and the particles' own volumes.
//  - Density diffusion (delta-SPH, or the Riemann solver's pressure diffusion) and the Riemann
//    flux's dissipation (momentum.flux riemann) only between particles of the same fluid: across
//    an interface they would smear the density jump, and their rho0 c0 is one fluid's. The
//    Riemann wall term (finish_fluid_rates) acts as with one fluid, with i's rho0 and c0.
//  - Walls: a wall particle is seen by fluid i as a particle of i's own fluid at the wall's
//    normalised density rho_w / rho0_ref (the reference fluid's equation of state gave rho_w,
//    Adami; materials.hpp), so its volume m/rho is the same for every phase, its impedance and
//    viscosity are i's, and p*_iw = (p_i + p_w)/2 as in eq. 7.
#include <cstdint>

#include "fluid_interactions.hpp"

namespace spate {

// What the multiphase pair terms read of neighbour j's fluid material (for a wall: ignored).
struct NeighbourFluid {
  float mass = 0.0f;
  float c0 = 0.0f;
  float viscosity = 0.0f;
};

SPATE_HD NeighbourFluid neighbour_fluid(const PhysicsParams& P, std::uint8_t material) {
  if (!P.is_fluid(material)) return NeighbourFluid{};
  const FluidMaterial& m = P.materials.of(material);
  return NeighbourFluid{m.mass, m.c0, m.viscosity};
}

// The same at temperature t: a fluid with a viscosity table (heat_transfer.hpp) takes mu(t).
SPATE_HD NeighbourFluid neighbour_fluid(const PhysicsParams& P, std::uint8_t material, float t) {
  NeighbourFluid n = neighbour_fluid(P, material);
  if (P.is_fluid(material)) n.viscosity = P.heat.viscosity(material, n.viscosity, t);
  return n;
}

// The contribution of neighbour j (of fluid properties Nj, see neighbour_fluid) to fluid particle
// i of material M, whose viscosity is mu_i (M.viscosity, or with a temperature table its own
// mu(T_i); a wall takes i's). Branch-free like fluid_pair_terms (selects, no jumps), so the CPU driver's loop
// over neighbours vectorises; zero beyond the support and for j = i. MovingWalls: as
// fluid_pair_terms (j.w is what continuity sees of j; free-slip faces slide for the artificial
// viscosity, vr_av). Riemann: as fluid_pair_terms.
template <class Kernel, int Dim, bool Gamma7 = true, bool MovingWalls = false, bool Riemann = true>
SPATE_HD FluidRates<Dim> multiphase_pair_terms(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                               const ParticleState<Dim>& j, const NeighbourFluid& Nj, float mu_i,
                                               const PairKinematics<Dim>& pk) {
  const bool j_is_fluid = P.is_fluid(j.material);
  const float j_fluid = j_is_fluid ? 1.0f : 0.0f;
  const float r2 = pk.r2, F = pk.F, inv_r2_eta = pk.inv_r2_eta, vr = pk.vr;
  const float same_fluid = j.material == i.material ? 1.0f : 0.0f;  // walls never match a fluid
  // A wall stands in for a particle of i's fluid at the wall's normalised density (see above).
  const float wall_scale = M.rho0 / P.materials.wall_fluid().rho0;
  const float rho_j = j_is_fluid ? j.rho : j.rho * wall_scale;
  const float m_j = j_is_fluid ? Nj.mass : M.mass;
  const float c_j = j_is_fluid ? Nj.c0 : M.c0;
  const float mu_j = j_is_fluid ? Nj.viscosity : mu_i;
  const float inv_rho_i = 1.0f / i.rho;
  const float volume_i = M.mass * inv_rho_i;
  const float volume_j = m_j / rho_j;

  const float z_i = i.rho * M.c0;
  const float z_j = rho_j * c_j;
  // Eq. 6, normalised continuity with the neighbour's volume; across an interface with the
  // velocity of the pair's acoustic interface instead of j's (see above): v_i - v* = Z_j/(Z_i+Z_j) v_ij.
  const float inv_z_sum = 1.0f / (z_i + z_j);
  // (Selected on a float: a select on `j_is_fluid && !same` is one the vectoriser rejects.)
  const float across = j_fluid * (1.0f - same_fluid);
  const float interface = across > 0.0f ? 2.0f * z_j * inv_z_sum : 1.0f;
  float drho = i.rho * volume_j * vr * F * interface;
  // Density diffusion and the Riemann options within i's fluid only (the terms of
  // fluid_pair_terms, times same_fluid).
  drho += density_diffusion<Gamma7>(P, M, same_fluid, i.rho, j.rho, pk.g_dot_rji, r2, F, inv_r2_eta, volume_j);
  RiemannPairTerms riemann{0.0f, 0.0f};
  if constexpr (Riemann) {
    riemann = riemann_pair_terms<Dim>(P, M, same_fluid, i, j, pk, volume_j);
    drho += riemann.density_rate;
  }

  // Eq. 7 with the acoustic interface pressure: p_i + p_j -> 2 p*_ij (plus, with momentum.flux
  // riemann, the limiter's dissipation between particles of one fluid); with
  // momentum.pressure_gradient difference, 2 p*_ij - 2 p_i (see above).
  const float p_interface = 2.0f * (z_j * i.p + z_i * j.p) * inv_z_sum;
  const float p_pair = (Riemann ? p_interface + riemann.p_dissipation : p_interface) - P.pressure_difference * 2.0f * i.p;
  // Monaghan (1992) artificial viscosity with the pair's mean sound speed and density.
  const float mu_ij = P.h * (pk.vr_av < 0.0f ? pk.vr_av : 0.0f) * inv_r2_eta;
  const float pi_ij = -artificial_alpha(P, j_fluid) * (M.c0 + c_j) * mu_ij / (i.rho + rho_j);
  const float radial = -(p_pair * inv_rho_i * volume_j + m_j * pi_ij) * F;
  // Eq. 8 with the harmonic mean of the two viscosities (0 when both fluids are inviscid).
  const float mu_sum = mu_i + mu_j;
  const float mu_pair = mu_sum > 0.0f ? 2.0f * mu_i * mu_j / mu_sum : 0.0f;
  const float laminar = mu_pair / M.mass * (volume_i * volume_i + volume_j * volume_j) * (r2 * F) * inv_r2_eta;

  return pair_rates<Dim, Riemann>(pk, radial, laminar, drho, j_fluid, volume_j);
}
template <class Kernel, int Dim, bool Gamma7 = true, bool MovingWalls = false, bool Riemann = true>
SPATE_HD FluidRates<Dim> multiphase_pair_terms(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                               const ParticleState<Dim>& j, const NeighbourFluid& Nj, float mu_i) {
  return multiphase_pair_terms<Kernel, Dim, Gamma7, MovingWalls, Riemann>(P, M, i, j, Nj, mu_i,
                                                                          pair_kinematics<Kernel, Dim, MovingWalls>(P, i, j));
}

}  // namespace spate
