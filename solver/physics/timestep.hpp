#pragma once
// Adaptive time step limits (Monaghan 1992; Morris et al. 1997): sound-speed CFL, acceleration,
// viscous diffusion and capillary waves (Brackbill et al. 1992). The global step is the minimum over every particle of every device.
#include <cmath>

#include "params.hpp"

namespace spate {

struct TimeStepControl {
  float cfl = 0.2f;
  float force_factor = 0.25f;
  float viscous_factor = 0.125f;
  float surface_tension_factor = 0.25f;
  float conduction_factor = 0.1f;  // dt <= 0.1 rho c_p h^2 / k (Cleary & Monaghan 1999)
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

// The smallest over the fluids (kinematic viscosity nu = mu / rho0; with a temperature table, its
// largest mu).
inline float viscous_time_step(const PhysicsParams& P, const TimeStepControl& c) {
  float dt = INFINITY;
  for (int m = 0; m < P.materials.fluids; ++m) {
    const FluidMaterial& M = P.materials.fluid[m];
    const float mu = P.heat.largest_viscosity(static_cast<std::uint8_t>(m), M.viscosity);  // a table's largest
    if (mu <= 0.0f) continue;
    const float dt_m = c.viscous_factor * P.h * P.h * M.rho0 / mu;
    dt = dt_m < dt ? dt_m : dt;
  }
  return dt;
}

// The capillary-wave limit dt <= 0.25 sqrt(rho h^3 / (2 pi sigma)) (Brackbill, Kothe & Zemach
// 1992; Adami, Hu & Adams 2010), over every pair of fluids with a coefficient, with the lighter
// fluid's rest density (the stricter of the two). Infinity without surface tension.
inline float surface_tension_time_step(const PhysicsParams& P, const TimeStepControl& c) {
  float dt = INFINITY;
  if (!P.surface_tension.on) return dt;
  const float h3 = P.h * P.h * P.h;
  for (int a = 0; a < P.materials.fluids; ++a) {
    for (int b = a + 1; b < P.materials.fluids; ++b) {
      const float sigma = P.surface_tension.sigma[a][b];
      if (sigma <= 0.0f) continue;
      const float rho = std::fmin(P.materials.fluid[a].rho0, P.materials.fluid[b].rho0);
      const float dt_ab = c.surface_tension_factor * std::sqrt(rho * h3 / (2.0f * 3.14159265f * sigma));
      dt = dt_ab < dt ? dt_ab : dt;
    }
  }
  return dt;
}

// The conduction limit (heat_transfer.hpp), over every thermal entry in use: fluids at their rest
// density, conducting walls and solids at theirs. Infinity without heat transfer.
inline float heat_time_step(const PhysicsParams& P, const TimeStepControl& c) {
  float dt = INFINITY;
  if (!P.heat.on) return dt;
  for (int m = 0; m < P.materials.count; ++m) {
    const ThermalMaterial& t = P.heat.material(static_cast<std::uint8_t>(m));
    if (t.condition != ThermalCondition::Conducting) continue;
    const float rho = P.is_fluid(static_cast<std::uint8_t>(m)) ? P.materials.fluid[m].rho0 : t.density;
    dt = std::fmin(dt, conduction_time_step(t, rho, P.h, c.conduction_factor));
  }
  return dt;
}

// The limits that do not depend on the particles' state: viscous diffusion, capillary waves and
// heat conduction.
inline float state_free_time_step(const PhysicsParams& P, const TimeStepControl& c) {
  const float viscous = viscous_time_step(P, c);
  const float capillary = surface_tension_time_step(P, c);
  return std::fmin(heat_time_step(P, c), capillary < viscous ? capillary : viscous);
}

}  // namespace spate
