#pragma once
// Walls that move: a solid or the whole tank follows a prescribed rigid motion, a translation d(t)
// of a reference point plus a rotation theta(t) about it (about z in 2D, about a fixed axis in 3D):
//   x(t) = c0 + d(t) + R(theta(t)) (x(0) - c0).
// The case's motion (solver/case/motion.*) is evaluated on the host in double precision once per
// step; the kernels get, per motion,
//   MotionState: velocity, angular velocity, centre, acceleration and angular acceleration at the
//                time the rates are evaluated, from which every wall particle's velocity and
//                acceleration follow (rigid body kinematics);
//   MotionStep:  the rigid map from t_n to t_n+1 that moves the wall particles in the predictor,
//                x' = c(t_n+1) + R(theta(t_n+1) - theta(t_n)) (x - c(t_n)), in double, so that a
//                particle's position is rounded to float once per step.
// A wall particle's material says which motion, if any, it follows (MaterialTable::motion).
#include <cstddef>

#include "host_device.hpp"
#include "vec.hpp"

namespace spate {

constexpr int kMaxMotions = 8;

struct MotionState {
  float velocity[3] = {0, 0, 0};              // of the reference point [m/s]
  float angular_velocity[3] = {0, 0, 0};      // [rad/s] (2D: z component)
  float centre[3] = {0, 0, 0};                // the reference point now [m]
  float acceleration[3] = {0, 0, 0};          // of the reference point [m/s2]
  float angular_acceleration[3] = {0, 0, 0};  // [rad/s2]
};

struct MotionStep {
  double from[3] = {0, 0, 0};  // the reference point at t_n
  double to[3] = {0, 0, 0};    // at t_n+1
  double rotation[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};  // R(theta(t_n+1) - theta(t_n))
};

// omega x r for the first Dim components (2D: omega along z).
template <int Dim>
SPATE_HD Vec<Dim> cross_omega(const float omega[3], const Vec<Dim>& r) {
  Vec<Dim> out;
  if constexpr (Dim == 2) {
    out[0] = -omega[2] * r[1];
    out[1] = omega[2] * r[0];
  } else {
    out[0] = omega[1] * r[2] - omega[2] * r[1];
    out[1] = omega[2] * r[0] - omega[0] * r[2];
    out[2] = omega[0] * r[1] - omega[1] * r[0];
  }
  return out;
}

// Velocity of the rigid body's point x: V + Omega x (x - c).
template <int Dim>
SPATE_HD Vec<Dim> rigid_velocity(const MotionState& m, const Vec<Dim>& x) {
  Vec<Dim> r;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) r[k] = x[k] - m.centre[k];
  const Vec<Dim> w = cross_omega<Dim>(m.angular_velocity, r);
  Vec<Dim> v;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) v[k] = m.velocity[k] + w[k];
  return v;
}

// Acceleration of the rigid body's point x: A + alpha x r + Omega x (Omega x r), r = x - c.
template <int Dim>
SPATE_HD Vec<Dim> rigid_acceleration(const MotionState& m, const Vec<Dim>& x) {
  Vec<Dim> r;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) r[k] = x[k] - m.centre[k];
  const Vec<Dim> tangential = cross_omega<Dim>(m.angular_acceleration, r);
  const Vec<Dim> centripetal = cross_omega<Dim>(m.angular_velocity, cross_omega<Dim>(m.angular_velocity, r));
  Vec<Dim> a;
  SPATE_UNROLL for (int k = 0; k < Dim; ++k) a[k] = m.acceleration[k] + tangential[k] + centripetal[k];
  return a;
}

// Moves wall particle i from t_n to t_n+1 (x: the position arrays, host vectors or device
// pointers; components beyond dim are untouched).
template <class Array>
SPATE_HD void apply_motion_step(const MotionStep& s, int dim, Array (&x)[3], std::size_t i) {
  double r[3] = {0, 0, 0};
  for (int k = 0; k < dim; ++k) r[k] = static_cast<double>(x[k][i]) - s.from[k];
  for (int k = 0; k < dim; ++k) {
    double v = s.to[k];
    for (int l = 0; l < dim; ++l) v += s.rotation[k][l] * r[l];
    x[k][i] = static_cast<float>(v);
  }
}

// Turns wall particle i's surface normal (params.hpp WallFrame: a moving solid's or tank's that
// slides) with the step's rotation, as apply_motion_step moves its position.
template <class Array>
SPATE_HD void turn_with_motion_step(const MotionStep& s, int dim, Array (&n)[3], std::size_t i) {
  double v[3] = {0, 0, 0};
  for (int k = 0; k < dim; ++k) v[k] = static_cast<double>(n[k][i]);
  for (int k = 0; k < dim; ++k) {
    double t = 0.0;
    for (int l = 0; l < dim; ++l) t += s.rotation[k][l] * v[l];
    n[k][i] = static_cast<float>(t);
  }
}

}  // namespace spate
