#pragma once
// Tait equation of state, eq. 9 of the paper, per fluid material:
//   p = c0^2 rho0 / gamma ((rho/rho0)^gamma - 1) + p_b
// with p_b the material's background pressure (0 unless a light phase needs one).
#include <cmath>

#include "host_device.hpp"
#include "materials.hpp"
#include "params.hpp"

namespace spate {

// gamma = 7 as an exact product: pow() would cost more than the rest of the particle update.
SPATE_HD float pow7(float x) {
  const float x2 = x * x;
  const float x3 = x2 * x;
  return x3 * x3 * x;
}

// x^gamma with the exact product for the usual gamma = 7.
SPATE_HD float tait_power(float x, float gamma) { return gamma == 7.0f ? pow7(x) : powf(x, gamma); }

SPATE_HD float tait_pressure(float rho, const FluidMaterial& m) {
  return m.tait_b * (tait_power(rho / m.rho0, m.gamma) - 1.0f) + m.background_pressure;
}

// The pressure a fluid particle carries: eq. 9, and with fluid.tension off not below 0. A free
// surface is at atmospheric pressure: a stretching sheet of water (a run-up jet, a splash) loses
// density in the weakly compressible model and would otherwise pull on itself and on the walls it
// slides along with a tension real water at atmospheric pressure does not sustain.
SPATE_HD float fluid_pressure(const PhysicsParams& P, const FluidMaterial& m, float rho) {
  const float p = tait_pressure(rho, m);
  return P.tension || p > 0.0f ? p : 0.0f;
}

// The floor of fluid material m's continuity density: its rest density when the fluid takes no
// tension (fluid.tension: false; eos.hpp fluid_pressure clips the pressure at 0), 0 otherwise.
SPATE_HD float density_floor(const PhysicsParams& P, std::uint8_t m) { return P.tension ? 0.0f : P.materials.of(m).rho0; }

// Inverse of eq. 9, used to give wall particles the density that matches their pressure.
SPATE_HD float tait_density(float p, const FluidMaterial& m) {
  return m.rho0 * powf((p - m.background_pressure) / m.tait_b + 1.0f, m.inv_gamma);
}

// (c / c0)^2 = (rho / rho0)^(gamma - 1): the Tait sound speed at density ratio s, squared and
// relative to c0. Gamma7 (a compile-time choice of the pair loops) keeps the exact product.
template <bool Gamma7>
SPATE_HD float tait_sound_speed_ratio2(float s, float gamma) {
  if constexpr (Gamma7) {
    const float s2 = s * s;
    return s2 * s2 * s2;
  } else {
    return powf(s, gamma - 1.0f);
  }
}

}  // namespace spate
