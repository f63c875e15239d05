#pragma once
// Kernel-weighted (Shepard) sampling of the fluid at an arbitrary point, for probes:
//   f(X) = sum_j f_j V_j W(X - x_j) / sum_j V_j W(X - x_j)
// The denominator alone is the fluid "fill fraction" used to find a free surface (0.5 at the
// surface, ~1 inside).
#include "fluid_interactions.hpp"

namespace spate {

template <int Dim>
struct ShepardSums {
  double weight = 0.0;  // sum V_j W
  double value = 0.0;   // sum f_j V_j W
};

// xj, rho_j, f_j of a fluid particle of material m_j.
template <class Kernel, int Dim>
SPATE_HD void accumulate_shepard(const PhysicsParams& P, const Vec<Dim>& at, const Vec<Dim>& xj, float rho_j, std::uint8_t m_j,
                                 float f_j, ShepardSums<Dim>& s) {
  const Vec<Dim> r = at - xj;
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return;
  const float vw = P.materials.of(m_j).mass / rho_j * Kernel::value(sqrtf(r2) * P.inv_h, P.kernel_norm);
  s.weight += vw;
  s.value += static_cast<double>(f_j) * vw;
}

// Pressure force exerted by fluid particle f on wall particle w (eq. 7 seen from the wall):
//   F_w = -m_w m_f (p_w + p_f) / (rho_w rho_f) grad_w W_wf
// (a wall particle has the mass of the fluid it bounds, as in the fluid's pair terms).
template <class Kernel, int Dim>
SPATE_HD Vec<Dim> wall_pressure_force(const PhysicsParams& P, const ParticleState<Dim>& w,
                                      const ParticleState<Dim>& f) {
  const Vec<Dim> r = w.x - f.x;
  const float r2 = dot(r, r);
  if (r2 >= P.support2 || r2 == 0.0f) return zero_vec<Dim>();
  const float F = kernel_gradient_factor<Kernel>(P, r2);
  const float m = P.materials.of(f.material).mass;
  return (-m * m * (w.p + f.p) / (w.rho * f.rho) * F) * r;
}

}  // namespace spate
