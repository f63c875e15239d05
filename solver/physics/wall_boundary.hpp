#pragma once
// Wall particles after Adami, Hu & Adams (2012), J. Comput. Phys. 231:7057: each wall particle takes
// the pressure that balances the surrounding fluid,
//   p_w = (sum_f p_f W_wf + (g - a_w) . sum_f rho_f r_wf W_wf) / sum_f W_wf,
// its density from the inverse EOS, and the mirrored fluid velocity (no slip) for the viscous term,
// u_w = 2 v_w - sum_f v_f W_wf / sum_f W_wf (their eq. 22-23), v_w and a_w the wall's prescribed
// velocity and acceleration (wall_motion.hpp; both zero for static walls). Why this and not DBC:
// see docs/physics.md.
#include "eos.hpp"
#include "fluid_interactions.hpp"

namespace spate {

template <int Dim>
struct WallSums {
  float w = 0.0f;
  float pw = 0.0f;
  Vec<Dim> rho_r_w = zero_vec<Dim>();
  Vec<Dim> v_w = zero_vec<Dim>();
};

template <class Kernel, int Dim>
SPATE_HD void accumulate_wall_pair(const PhysicsParams& P, const Vec<Dim>& x_wall,
                                   const ParticleState<Dim>& fluid, WallSums<Dim>& s) {
  const Vec<Dim> r = x_wall - fluid.x;  // r_wf
  const float r2 = dot(r, r);
  if (r2 >= P.support2) return;
  const float w = Kernel::value(sqrtf(r2) * P.inv_h, P.kernel_norm);
  s.w += w;
  s.pw += fluid.p * w;
  for (int k = 0; k < Dim; ++k) {
    s.rho_r_w[k] += fluid.rho * w * r[k];
    s.v_w[k] += fluid.v[k] * w;
  }
}

template <int Dim>
struct WallState {
  float p;
  float rho;
  Vec<Dim> v;  // extrapolated no-slip velocity
};

// The pressure the fluid around a wall point implies there (s.w > 0), before any clipping: the
// kernel-weighted fluid pressure extrapolated to the point along the hydrostatic gradient. It is
// also what a wall-pressure sensor reads at a point of its disc (sim/probes.cpp). a_w: the wall's
// acceleration there.
template <int Dim>
SPATE_HD float adami_pressure(const PhysicsParams& P, const WallSums<Dim>& s, const Vec<Dim>& a_w) {
  float g_dot = 0.0f;
  for (int k = 0; k < Dim; ++k) g_dot += (P.gravity[k] + P.body_force[k] - a_w[k]) * s.rho_r_w[k];
  return (s.pw + g_dot) / s.w;
}

// Negative wall pressures would glue fluid to walls at a free surface; they are clipped to zero.
// The density comes from the equation of state of the fluid the wall bounds (materials.hpp).
// `material` and `x` are the wall particle's: a moving wall adds its motion (wall_motion.hpp).
template <int Dim>
SPATE_HD WallState<Dim> finish_wall(const PhysicsParams& P, const WallSums<Dim>& s, std::uint8_t material, const Vec<Dim>& x) {
  const FluidMaterial& M = P.materials.wall_fluid();
  WallState<Dim> out{0.0f, M.rho0, zero_vec<Dim>()};
  if (s.w <= 0.0f) return out;
  const MotionState* motion = P.motion_of(material);
  // (g - a_w): the wall's acceleration at its own position (zero for a static wall).
  const Vec<Dim> a_w = motion ? rigid_acceleration<Dim>(*motion, x) : zero_vec<Dim>();
  const float p = adami_pressure(P, s, a_w);
  out.p = p > 0.0f ? p : 0.0f;
  out.rho = tait_density(out.p, M);
  if (motion) {
    const Vec<Dim> v_w = rigid_velocity<Dim>(*motion, x);
    for (int k = 0; k < Dim; ++k) out.v[k] = 2.0f * v_w[k] - s.v_w[k] / s.w;
  } else {
    for (int k = 0; k < Dim; ++k) out.v[k] = -s.v_w[k] / s.w;
  }
  return out;
}

}  // namespace spate
