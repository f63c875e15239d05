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

// The step one fluid particle allows. A particle whose speed is NaN allows 0, not NaN: the global
// step is a minimum (an OpenMP reduction on the CPU, a CUB reduction on the GPU) built on `<`,
// which keeps or drops a NaN depending on where the reduction meets it; 0 is the same minimum in
// any order, and the run stops with "the time step collapsed to 0". (A NaN acceleration already
// gives a number: the sound-speed limit, `acc_magnitude > 0` being false; the health check then
// names the particle once its velocity follows.)
// M is the particle's fluid material.
SPATE_HD float particle_time_step(const PhysicsParams& P, const FluidMaterial& M, const TimeStepControl& c, float speed,
                                  float acc_magnitude) {
  float dt = c.cfl * P.h / (M.c0 + speed);
  if (acc_magnitude > 0.0f) {
    const float dt_f = c.force_factor * sqrtf(P.h / acc_magnitude);
    dt = dt_f < dt ? dt_f : dt;
  }
  return dt == dt ? dt : 0.0f;  // NaN != NaN (no -ffast-math here)
}

// The smallest over the fluids (kinematic viscosity nu = mu / rho0).
inline float viscous_time_step(const PhysicsParams& P, const TimeStepControl& c) {
  float dt = INFINITY;
  for (int m = 0; m < P.materials.fluids; ++m) {
    const FluidMaterial& M = P.materials.fluid[m];
    if (M.viscosity <= 0.0f) continue;
    const float dt_m = c.viscous_factor * P.h * P.h * M.rho0 / M.viscosity;
    dt = dt_m < dt ? dt_m : dt;
  }
  return dt;
}

}  // namespace spate
