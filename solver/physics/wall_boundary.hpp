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

// What fluid neighbour `fluid` adds to a wall particle's sums: W_wf and its products (all zero
// beyond the support, where nothing is added). Branch-free, so that the CPU driver computes it
// vectorised over a wall particle's neighbours before adding them up in order (add_wall_pair).
template <class Kernel, int Dim>
SPATE_HD WallSums<Dim> wall_pair_terms(const PhysicsParams& P, const Vec<Dim>& x_wall, const ParticleState<Dim>& fluid) {
  const Vec<Dim> r = x_wall - fluid.x;  // r_wf
  const float r2 = dot(r, r);
  // The kernel for every pair, then selected: a conditional read of P is a masked load, which
  // the vectoriser rejects on AVX2.
  const float value = Kernel::value(sqrtf(r2) * P.inv_h, P.kernel_norm);
  const float w = r2 < P.support2 ? value : 0.0f;
  WallSums<Dim> t;
  t.w = w;
  t.pw = fluid.p * w;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
    t.rho_r_w[k] = fluid.rho * w * r[k];
    t.v_w[k] = fluid.v[k] * w;
  }
  return t;
}

// The sums in the order neighbours are visited (every device and driver adds them in that order).
template <int Dim>
SPATE_HD void add_wall_pair(WallSums<Dim>& s, const WallSums<Dim>& t) {
  s.w += t.w;
  s.pw += t.pw;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
    s.rho_r_w[k] += t.rho_r_w[k];
    s.v_w[k] += t.v_w[k];
  }
}

template <class Kernel, int Dim>
SPATE_HD void accumulate_wall_pair(const PhysicsParams& P, const Vec<Dim>& x_wall,
                                   const ParticleState<Dim>& fluid, WallSums<Dim>& s) {
  add_wall_pair(s, wall_pair_terms<Kernel, Dim>(P, x_wall, fluid));
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

// Negative wall pressures would glue fluid to walls at a free surface; they are clipped to zero
// unless the case says the walls hold tension (fluid.wall_tension, for flows without a free surface:
// there the clip lets fluid in tension, which pulls on itself with p_i + p_j < 0 but on the wall with
// p_i alone, tear off the wall; docs/studies/cylinder-flow.md).
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
  out.p = p > 0.0f || P.wall_tension ? p : 0.0f;
  out.rho = tait_density(out.p, M, P.portable_eos);
  if (motion) {
    const Vec<Dim> v_w = rigid_velocity<Dim>(*motion, x);
    for (int k = 0; k < Dim; ++k) out.v[k] = 2.0f * v_w[k] - s.v_w[k] / s.w;
  } else {
    for (int k = 0; k < Dim; ++k) out.v[k] = -s.v_w[k] / s.w;
  }
  return out;
}

// Free-slip walls (tank.free_slip, a solid's free_slip; Hysing et al.'s rising bubble has free-slip
// sides): a wall particle under a free-slip face (its frame, params.hpp WallFrame: a box tank's face
// or a shaped wall's own normal n; a box tank's corners stay no-slip) keeps Adami's mirrored normal
// component, (2 w - v~) . n with w the wall's velocity (no penetration), but takes the fluid's own
// tangential velocity, so the viscous term (eq. 8) exerts no shear along the wall:
//   u_w = v~ + 2 ((w - v~) . n) n   (a wall at rest: v~ - 2 (v~ . n) n).
// The artificial viscosity sees that tangential velocity too (sliding_velocity), so it exerts no
// friction there.
template <int Dim>
SPATE_HD void apply_free_slip(const WallFrame<Dim>& face, const WallSums<Dim>& s, WallState<Dim>& st) {
  Vec<Dim> v;  // v~, the fluid's kernel-weighted velocity around the wall particle
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) v[k] = s.v_w[k] / s.w;
  const float un = dot(face.w - v, face.n);
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) st.v[k] = v[k] + 2.0f * un * face.n[k];
}

// The friction velocity u* of the smooth-wall law of the wall for a tangential speed `u` at distance
// `y` from the wall, kinematic viscosity `nu`: u+ = y+ in the viscous sublayer (y+ < 11.2, where the
// two meet), u+ = ln(y+) / kappa + B above it (kappa = 0.41, B = 5.2; u+ = u / u*, y+ = y u* / nu).
// Returns u*^2 (the wall shear stress over rho). Newton's method on u* from the log law's value at
// u* = u / 20, a fixed number of steps (deterministic, the same on every device): from y+ = 11 to
// 1e6 the sixth step is converged to float precision.
SPATE_HD float log_law_u_star2(float u, float y, float nu) {
  constexpr float kappa = 0.41f, B = 5.2f, y_plus_sublayer = 11.2f;
  if (u <= 0.0f) return 0.0f;
  if (u * y / nu < y_plus_sublayer * y_plus_sublayer) return nu * u / y;  // sublayer: y+ = u+ => y+^2 = u y / nu
  float us = u / 20.0f;
  for (int it = 0; it < 6; ++it) {
    const float l = logf(y * us / nu) / kappa + B;  // u+ at this u*
    us -= (us * l - u) / (l + 1.0f / kappa);
    us = us > 1e-6f * u ? us : 1e-6f * u;
  }
  return us * us;
}

// Turbulent wall shear (tank.wall_shear or a solid's wall_shear: log_law), a wall function in Adami's
// scheme: the laminar term (eq. 8) sees the wall particle's extrapolated velocity, and across the
// distance d from the wall particle to the fluid around it (its kernel-weighted position, along the
// face's normal n) exerts mu (u_t - v_w) / d. The wall particle takes the tangential velocity that
// makes that shear rho u*^2 of the log law (log_law_u_star2) at the fluid's distance y = d - depth
// from the face (depth: the wall particle's own distance behind it; params.hpp WallFrame):
//   v_w,t = u_t (1 - u*^2 d / (nu |u_t|)).
// In the viscous sublayer (u*^2 = nu |u_t| / y) that is v_w,t = -u_t depth / y, the linear
// extrapolation of a linear profile through the face, i.e. no slip; at y+ ~ 100-1000, where the
// particles next to a dam-break floor are, the shear is tens of times the laminar term's. The
// normal component keeps Adami's mirror (no penetration). A moving wall (a solid's or a shaped
// tank's motion, a floating solid; face.w its velocity there) applies the law to the fluid's
// velocity relative to it: u_t is the tangential part of v~ - w and v_w,t = w_t + u_t (1 - ...), so
// water moving with the wall feels no shear (for a wall at rest w = 0 and the formula is the one
// above, bit for bit). A box tank has no per-particle frame to move with it: the loader refuses the
// law on a moving box tank; its corners keep Adami's. With several fluids nu is the walls'
// reference fluid's (materials.hpp wall_fluid). Only runs with the key execute it.
template <int Dim>
SPATE_HD void apply_log_law(const PhysicsParams& P, const WallFrame<Dim>& face, const WallSums<Dim>& s, WallState<Dim>& st) {
  const FluidMaterial& M = P.materials.wall_fluid();
  // s.rho_r_w = sum rho_f (x_w - x_f) W: the fluid's mean offset from the wall particle, with rho0
  // for rho_f (within the weak compressibility's 1%).
  const float d = -dot(s.rho_r_w, face.n) / (M.rho0 * s.w);
  const float y = d - face.depth;
  if (y <= 0.0f) return;
  Vec<Dim> v;  // v~ - w, the fluid's velocity relative to the wall, and its tangential part
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) v[k] = s.v_w[k] / s.w - face.w[k];
  const float vn = dot(v, face.n);
  Vec<Dim> t;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) t[k] = v[k] - vn * face.n[k];
  const float u = sqrtf(dot(t, t));
  if (u <= 0.0f) return;
  const float nu = M.viscosity / M.rho0;
  if (nu <= 0.0f) return;  // an inviscid fluid has no law of the wall: Adami's no slip stays
  const float factor = 1.0f - log_law_u_star2(u, y, nu) * d / (nu * u);
  const float wn = dot(st.v, face.n);  // Adami's mirrored normal component, kept
  const float w_n = dot(face.w, face.n);
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) st.v[k] = (face.w[k] - w_n * face.n[k]) + factor * t[k] + wn * face.n[k];
}

// The wall particle's velocity for the laminar term beyond Adami's no slip: free slip or the log law,
// as its face says (params.hpp WallFrame). The one call of the wall pass after finish_wall.
template <int Dim>
SPATE_HD void apply_wall_shear(const PhysicsParams& P, const WallFrame<Dim>& face, const WallSums<Dim>& s, WallState<Dim>& st) {
  if (s.w <= 0.0f) return;
  if (face.shear == FaceShear::FreeSlip) apply_free_slip<Dim>(face, s, st);
  else if (face.shear == FaceShear::LogLaw) apply_log_law<Dim>(P, face, s, st);
}
// The same for wall particle w of `f` at x_wall; nothing to do (no frame looked up) in runs where
// every wall is Adami's no slip.
template <int Dim, class Fields>
SPATE_HD void apply_wall_shear(const PhysicsParams& P, const Fields& f, std::uint32_t w, const Vec<Dim>& x_wall, const WallSums<Dim>& s,
                               WallState<Dim>& st) {
  if (P.walls_shear_otherwise()) apply_wall_shear<Dim>(P, wall_frame<Dim>(P, f, w, x_wall), s, st);
}

}  // namespace spate
