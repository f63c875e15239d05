#pragma once
// The SPH velocity gradient of a particle, (grad v)_i = sum_j V_j (v_j - v_i) (x) grad_i W_ij, the
// difference form (exact for a uniform velocity, also where the kernel is cut), with a wall's
// extrapolated no-slip velocity for v_j: the shear the wall imposes. Read by SPS turbulence
// (turbulence.hpp, with V_j = m_j / rho_j) and by the shifting's velocity correction (shifting.hpp,
// with V_j = m / rho0 as its other sums).
#include "fluid_interactions.hpp"

namespace spate {

// The velocity gradient sums: g[a][b] = d v_b / d x_a.
template <int Dim>
struct VelocityGradient {
  float g[Dim][Dim] = {};
};

// Neighbour j's term of particle i's velocity gradient, V_j (v_j - v_i) (x) grad_i W_ij into
// t[a][b] (volume_j = m_j / rho_j; v_j a wall's extrapolated no-slip velocity). Branch-free (beyond
// the support F = 0), for the CPU backend's vectorised loop over neighbours inside the support.
template <class Kernel, int Dim>
SPATE_HD void velocity_gradient_term(const PhysicsParams& P, const Vec<Dim>& xi, const Vec<Dim>& vi, const Vec<Dim>& xj,
                                     const Vec<Dim>& vj, float volume_j, float (&t)[Dim][Dim]) {
  const Vec<Dim> r = xi - xj;
  const float vF = volume_j * kernel_gradient_factor<Kernel>(P, dot(r, r));
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    SPATE_UNROLL for (int b = 0; b < Dim; ++b) t[a][b] = vF * r[a] * (vj[b] - vi[b]);
  }
}

// The same added to the sums, for a neighbour inside the support (none beyond it).
template <class Kernel, int Dim>
SPATE_HD void accumulate_velocity_gradient(const PhysicsParams& P, const ParticleState<Dim>& i, const ParticleState<Dim>& j,
                                           float volume_j, VelocityGradient<Dim>& s) {
  const Vec<Dim> r = i.x - j.x;
  if (dot(r, r) >= P.support2) return;  // as the CPU backend selects neighbours (sps_passes.cpp)
  float t[Dim][Dim];
  velocity_gradient_term<Kernel, Dim>(P, i.x, i.v, j.x, j.v, volume_j, t);
  SPATE_UNROLL for (int a = 0; a < Dim; ++a) {
    SPATE_UNROLL for (int b = 0; b < Dim; ++b) s.g[a][b] += t[a][b];
  }
}

}  // namespace spate
