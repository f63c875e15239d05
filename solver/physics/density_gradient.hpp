#pragma once
// The delta-SPH density diffusion of Antuono et al. (2010, Comput. Phys. Commun. 181:532), the form
// Marrone et al. (2011, Comput. Methods Appl. Mech. Engrg. 200:1526) use for violent impacts
// (`density.diffusion: antuono`):
//   D_i = delta h c0 sum_j psi_ij (x_j - x_i) . grad_i W_ij / (|x_j - x_i|^2 + eta^2) V_j,
//   psi_ij = 2 (rho_j - rho_i) - (<grad rho>_i + <grad rho>_j) . (x_j - x_i),
// with the renormalised density gradient (Randles & Libersky 1996)
//   <grad rho>_i = L_i sum_j (rho_j - rho_i) grad_i W_ij V_j,   L_i = [sum_j (x_j - x_i) (x) grad_i W_ij V_j]^-1.
// psi_ij vanishes for any linear density field, hydrostatic or dynamic, so only the second-order
// part of the density (the noise) diffuses; the Fourtakas et al. variant (fluid_interactions.hpp)
// takes out the hydrostatic part alone and also diffuses the linear part of a dynamic pressure field,
// such as the one in front of an impact. Sums over the neighbours of i's own fluid (V_j = m / rho_j;
// walls and other fluids take no part, as in the other diffusion variants).
//
// Two passes over the neighbours (backend/particle_updates.hpp), with a halo refresh of the gradient
// in between: (1) the gradient of the owned fluid particles, (2) D_i added to their density rate
// after the fluid pass (whose own diffusion is off for this variant).
#include <cstdint>

#include "fluid_interactions.hpp"

namespace spate {

// L_i^-1 is the identity for a full support; at a flat free surface its normal moment is about
// 0.6, at an edge of a block of fluid about 0.37 along each cut axis, in a 3D corner 0.31 (with
// off-diagonal 0.08: det 0.025). A neighbourhood whose det(L_i^-1) is below
// kMinRenormalisationMoment^Dim (0.0625 in 2D, 0.0156 in 3D: a quarter per axis) is too sparse to
// renormalise: such a particle (spray, a jet's tip) takes a zero
// gradient, i.e. the plain difference of Molteni & Colagrossi for its half of psi.
constexpr float kMinRenormalisationMoment = 0.25f;

// The sums of pass 1: the renormalisation matrix L_i^-1 (symmetric: (x_j - x_i) (x) grad_i W_ij =
// -F r_ij (x) r_ij) and the raw gradient sum_j (rho_j - rho_i) grad_i W_ij V_j.
template <int Dim>
struct DensityGradientSums {
  float m[Dim][Dim] = {};
  Vec<Dim> raw = zero_vec<Dim>();
};

template <class Kernel, int Dim>
SPATE_HD void accumulate_density_gradient(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                          const ParticleState<Dim>& j, DensityGradientSums<Dim>& s) {
  if (j.material != i.material) return;
  const Vec<Dim> r = i.x - j.x;
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return;
  const float F = kernel_gradient_factor<Kernel>(P, r2);
  const float vF = M.mass / j.rho * F;
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    s.raw[a] += (j.rho - i.rho) * vF * r[a];
    SPATE_UNROLL for (int b = 0; b < Dim; ++b) s.m[a][b] -= vF * r[a] * r[b];
  }
}

// L_i times the raw gradient: the renormalised gradient, or zero where det(L_i^-1) is below
// kMinRenormalisationMoment^Dim.
template <int Dim>
SPATE_HD Vec<Dim> renormalised_gradient(const DensityGradientSums<Dim>& s) {
  Vec<Dim> out = zero_vec<Dim>();
  const auto& m = s.m;
  if constexpr (Dim == 2) {
    const float det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    if (!(det > kMinRenormalisationMoment * kMinRenormalisationMoment)) return out;
    out[0] = (m[1][1] * s.raw[0] - m[0][1] * s.raw[1]) / det;
    out[1] = (m[0][0] * s.raw[1] - m[1][0] * s.raw[0]) / det;
  } else {
    const float c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    const float c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    const float c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    const float det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    if (!(det > kMinRenormalisationMoment * kMinRenormalisationMoment * kMinRenormalisationMoment)) return out;
    // The inverse of a symmetric matrix is its cofactor matrix over det (symmetric as well).
    const float c11 = m[0][0] * m[2][2] - m[0][2] * m[2][0];
    const float c12 = m[0][1] * m[2][0] - m[0][0] * m[2][1];
    const float c22 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    const float inv[3][3] = {{c00, c01, c02}, {c01, c11, c12}, {c02, c12, c22}};
    SPATE_UNROLL for (int a = 0; a < 3; ++a) out[a] = (inv[a][0] * s.raw[0] + inv[a][1] * s.raw[1] + inv[a][2] * s.raw[2]) / det;
  }
  return out;
}

// Neighbour j's term of D_i (pass 2), with both particles' renormalised gradients.
template <class Kernel, int Dim>
SPATE_HD float antuono_diffusion_term(const PhysicsParams& P, const FluidMaterial& M, const ParticleState<Dim>& i,
                                      const Vec<Dim>& grad_i, const ParticleState<Dim>& j, const Vec<Dim>& grad_j) {
  if (j.material != i.material) return 0.0f;
  const Vec<Dim> r = i.x - j.x;  // x_i - x_j = -(x_j - x_i)
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return 0.0f;
  const float F = kernel_gradient_factor<Kernel>(P, r2);
  // psi_ij / 2 = (rho_j - rho_i) - (grad_i + grad_j) . (x_j - x_i) / 2
  const float drho_ji = (j.rho - i.rho) + 0.5f * dot(grad_i + grad_j, r);
  return diffusion_flux(P, M, 1.0f, drho_ji, r2, F, 1.0f / (r2 + P.eta2), M.mass / j.rho);
}

}  // namespace spate
