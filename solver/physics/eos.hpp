#pragma once
// Tait equation of state, eq. 9 of the paper: p = c0^2 rho0 / gamma ((rho/rho0)^gamma - 1).
#include <cmath>

#include "host_device.hpp"

namespace spate {

// gamma = 7 as an exact product: pow() would cost more than the rest of the particle update.
SPATE_HD float pow7(float x) {
  const float x2 = x * x;
  const float x3 = x2 * x;
  return x3 * x3 * x;
}

SPATE_HD float tait_pressure(float rho, float rho0, float tait_b) {
  return tait_b * (pow7(rho / rho0) - 1.0f);
}

// Inverse of eq. 9, used to give wall particles the density that matches their pressure.
SPATE_HD float tait_density(float p, float rho0, float tait_b) {
  return rho0 * powf(p / tait_b + 1.0f, 1.0f / 7.0f);
}

}  // namespace spate
