#pragma once
// Adaptive time step limits (Monaghan 1992; Morris et al. 1997): sound-speed CFL, acceleration and
// viscous diffusion. The global step is the minimum over every particle of every device.
#include <cmath>

#include "params.hpp"

namespace spate {

struct TimeStepControl {
  float cfl = 0.2f;
  float force_factor = 0.25f;
  float viscous_factor = 0.125f;
};

SPATE_HD float particle_time_step(const PhysicsParams& P, const TimeStepControl& c, float speed,
                                  float acc_magnitude) {
  float dt = c.cfl * P.h / (P.c0 + speed);
  if (acc_magnitude > 0.0f) {
    const float dt_f = c.force_factor * sqrtf(P.h / acc_magnitude);
    dt = dt_f < dt ? dt_f : dt;
  }
  return dt;
}

inline float viscous_time_step(const PhysicsParams& P, const TimeStepControl& c) {
  if (P.viscosity <= 0.0f) return INFINITY;
  return c.viscous_factor * P.h * P.h * P.rho0 / P.viscosity;
}

}  // namespace spate
