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

// The step one fluid particle allows. A particle whose speed or acceleration is NaN allows 0, not
// NaN: the global step is a minimum (an OpenMP reduction on the CPU, a CUB reduction on the GPU)
// built on `<`, which keeps or drops a NaN depending on where the reduction meets it; 0 is the
// same minimum in any order, and the run stops with "the time step collapsed to 0".
SPATE_HD float particle_time_step(const PhysicsParams& P, const TimeStepControl& c, float speed,
                                  float acc_magnitude) {
  float dt = c.cfl * P.h / (P.c0 + speed);
  if (acc_magnitude > 0.0f) {
    const float dt_f = c.force_factor * sqrtf(P.h / acc_magnitude);
    dt = dt_f < dt ? dt_f : dt;
  }
  const bool number = dt == dt && acc_magnitude == acc_magnitude;  // NaN != NaN (no -ffast-math here)
  return number ? dt : 0.0f;
}

inline float viscous_time_step(const PhysicsParams& P, const TimeStepControl& c) {
  if (P.viscosity <= 0.0f) return INFINITY;
  return c.viscous_factor * P.h * P.h * P.rho0 / P.viscosity;
}

}  // namespace spate
