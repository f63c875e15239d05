#pragma once
// The natural scale of a stored particle field, for comparisons with a relative tolerance
// (`spate compare --scaled-tolerance`, the GPU-against-CPU checks): a difference of X times the
// scale means the same thing in a 2 mm dam break and a 50 um channel.
#include <string_view>

#include "../physics/params.hpp"

namespace spate {

// Positions: dp. Velocities: c0 (weakly compressible SPH keeps speeds below c0 / 10).
// Density: rho0. Pressure: rho0 c0^2 (a density off by a fraction e gives e rho0 c0^2, eq. 9).
// Accelerations: c0^2 / h (the pressure gradient of a 1 % density jump over h is 0.01 c0^2 / h).
// Density rates: rho0 c0 / h. Temperatures (heat transfer): 1 K; their rates 1 K alpha / h^2, alpha
// = k / (rho0 c_p) of the first fluid (the rate of a 1 K bump over h). Anything else (material,
// id): 0, compared exactly. c0 and rho0 are the first fluid's (the case constants).
inline double field_scale(std::string_view field, const PhysicsParams& P) {
  auto is = [&](std::initializer_list<std::string_view> names) {
    for (auto n : names)
      if (field == n) return true;
    return false;
  };
  const FluidMaterial& fluid = P.materials.fluid[0];
  const double h = P.h, c0 = fluid.c0, rho0 = fluid.rho0;
  if (is({"x", "y", "z"})) return P.dp;
  if (is({"vx", "vy", "vz"})) return c0;
  if (is({"density"})) return rho0;
  if (is({"pressure"})) return rho0 * c0 * c0;
  if (is({"ax", "ay", "az", "ax_prev", "ay_prev", "az_prev"})) return c0 * c0 / h;
  if (is({"density_rate", "density_rate_prev"})) return rho0 * c0 / h;
  if (is({"temperature", "temperature_residual"})) return 1.0;
  if (is({"temperature_rate"}) && P.heat.on) {
    const ThermalMaterial& t = P.heat.material(0);
    return t.specific_heat > 0 ? t.conductivity / (rho0 * t.specific_heat) / (h * h) : 0.0;
  }
  return 0.0;
}

}  // namespace spate
