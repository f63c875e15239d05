#pragma once
// Surface tension between fluids: the continuum surface force (Brackbill, Kothe & Zemach 1992) in
// the SPH form of Adami, Hu & Adams (2010, J. Comput. Phys. 229:5011), in two passes over the
// neighbours of every fluid particle (a halo refresh of the colour gradient in between):
//
//  1. Colour gradient (Adami et al. eqs. 12 and 14 with their inter-particle averaged colour):
//       grad C_i = (1/V_i) sum_j (V_i^2 + V_j^2) Ct_ij grad_i W_ij,
//       Ct_ij = (rho_j C_i + rho_i C_j) / (rho_i + rho_j).
//     The colour is taken relative to i: C_i = 0 and C_j = sigma_ij / sigma_i (1 for a particle of
//     the other fluid of a pair, 0 for i's own fluid and for walls), sigma_i the largest
//     coefficient of i's fluid. With C_i = 0 the sum is the difference form, exactly 0 inside a
//     phase; the density weighting puts the larger share of the colour jump on the heavy side,
//     so that both sides of an interface get the same acceleration sigma kappa |grad C| / rho
//     (no spurious shear at a density ratio of 10 or 1000). grad C points out of i's fluid.
//  2. Curvature from Adami's reproducing divergence of the unit normal n = grad C / |grad C|:
//       div n_i = d sum_j phi_ij (n_i - s_ij n_j) . grad_i W_ij V_j / sum_j phi_ij r_ij . grad_i W_ij V_j,
//     exact for a linear normal field whatever the neighbours present; s_ij = -1 across an
//     interface (the other fluid's normal points the other way), phi_ij = 1 when j is a fluid
//     particle with a defined normal (|grad C_j| h > kNormalThreshold), else 0, so particles away
//     from the interface, walls and the truncated support near them drop out of both sums. Then
//       kappa_i = -div n_i,   a_i = sigma_i kappa_i grad C_i / rho_i
//     (the force per volume sigma kappa n delta with delta = |grad C|), which points into the
//     fluid of positive curvature on both sides of the interface.
// Two fluids: exactly sigma kappa grad C. More fluids meeting at one particle: the colour of each
// neighbour is weighted by its pair's coefficient, one normal per particle (no triple-line model).
// No wetting model: walls do not carry colour. Chosen at dispatch (PhysicsParams::surface_tension
// on), so runs without a coefficient never execute any of it. docs/physics.md, "Surface tension".
#include <cstdint>

#include "fluid_interactions.hpp"

namespace spate {

// |grad C| h below which a particle has no normal (Morris 2000 uses 0.01 / h as well).
constexpr float kNormalThreshold = 0.01f;

// The colour of neighbour j (fluid material mj) seen from a particle of fluid mi: sigma_ij / sigma_i.
SPATE_HD float neighbour_colour(const PhysicsParams& P, std::uint8_t mi, std::uint8_t mj) {
  if (!P.is_fluid(mj) || mi == mj) return 0.0f;
  const float sigma_i = P.surface_tension.largest[mi];
  return sigma_i > 0.0f ? P.surface_tension.sigma[mi][mj] / sigma_i : 0.0f;
}

// One neighbour's term of grad C_i (pass 1), to be summed and finally divided by V_i.
template <class Kernel, int Dim>
SPATE_HD Vec<Dim> colour_gradient_term(const PhysicsParams& P, const ParticleState<Dim>& i, float volume_i,
                                       const ParticleState<Dim>& j) {
  Vec<Dim> out = zero_vec<Dim>();
  const float c_j = neighbour_colour(P, i.material, j.material);
  if (c_j == 0.0f) return out;
  const Vec<Dim> r = i.x - j.x;
  const float r_len = sqrtf(dot(r, r));
  const float F = Kernel::gradient_factor(r_len * P.inv_h, P.gradient_norm, P.inv_h2);
  const float volume_j = P.materials.of(j.material).mass / j.rho;
  const float colour = i.rho / (i.rho + j.rho) * c_j;
  const float w = (volume_i * volume_i + volume_j * volume_j) * colour * F;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) out[k] = w * r[k];
  return out;
}

// Whether a colour gradient defines a normal.
template <int Dim>
SPATE_HD bool has_normal(const PhysicsParams& P, const Vec<Dim>& grad_c) {
  const float t = kNormalThreshold * P.inv_h;
  return dot(grad_c, grad_c) > t * t;
}

// The sums of the reproducing divergence (pass 2).
struct DivergenceSums {
  float numerator = 0.0f;
  float denominator = 0.0f;
};

// Neighbour j's terms of div n_i: i of unit normal n_i; j at x_j with colour gradient grad_c_j.
template <class Kernel, int Dim>
SPATE_HD void accumulate_divergence(const PhysicsParams& P, const ParticleState<Dim>& i, const Vec<Dim>& n_i,
                                    const ParticleState<Dim>& j, const Vec<Dim>& grad_c_j, DivergenceSums& s) {
  if (!P.is_fluid(j.material) || !has_normal<Dim>(P, grad_c_j)) return;
  const Vec<Dim> r = i.x - j.x;
  const float r2 = dot(r, r);
  const float F = kernel_gradient_factor<Kernel>(P, r2);
  const float volume_j = P.materials.of(j.material).mass / j.rho;
  const float sign = j.material == i.material ? 1.0f : -1.0f;
  const float inv_len = sign / sqrtf(dot(grad_c_j, grad_c_j));
  float dn_r = 0.0f;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) dn_r += (n_i[k] - grad_c_j[k] * inv_len) * r[k];
  s.numerator += dn_r * F * volume_j;
  s.denominator += r2 * F * volume_j;
}

// The surface-tension acceleration of i (of colour gradient grad_c_i) from the divergence sums.
template <int Dim>
SPATE_HD Vec<Dim> surface_tension_acceleration(const PhysicsParams& P, const ParticleState<Dim>& i, const Vec<Dim>& grad_c_i,
                                               const DivergenceSums& s) {
  Vec<Dim> a = zero_vec<Dim>();
  if (s.denominator == 0.0f) return a;
  const float kappa = -static_cast<float>(Dim) * s.numerator / s.denominator;
  const float scale = P.surface_tension.largest[i.material] * kappa / i.rho;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) a[k] = scale * grad_c_i[k];
  return a;
}

}  // namespace spate
