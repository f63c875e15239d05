#pragma once
// Velocity-Verlet (kick-drift-kick) with a predicted velocity and density for the force evaluation,
// one force evaluation per step (second order; symplectic for velocity-independent forces):
//   predict:  x += dt v + dt^2/2 a;  v_pred = v + dt a;  rho_pred = rho + dt D
//   evaluate a', D' at (x, v_pred, rho_pred)
//   correct:  v = v_pred + dt/2 (a' - a);  rho = rho_pred + dt/2 (D' - D)
// i.e. v^{n+1} = v^n + dt/2 (a^n + a^{n+1}), the trapezoidal kick.
#include "host_device.hpp"

namespace spate {

SPATE_HD void predict_component(float& x, float& v, float a, float dt) {
  x += dt * v + 0.5f * dt * dt * a;
  v += dt * a;
}

SPATE_HD void predict_density(float& rho, float density_rate, float dt) { rho += dt * density_rate; }

SPATE_HD void correct(float& value, float new_rate, float old_rate, float dt) {
  value += 0.5f * dt * (new_rate - old_rate);
}

// The continuity density after the corrector, not below `floor` (density_floor). Without it a
// stretching sheet that takes no tension, which no longer pulls itself together, would thin out
// without bound.
SPATE_HD void correct_density(float& rho, float new_rate, float old_rate, float dt, float floor) {
  correct(rho, new_rate, old_rate, dt);
  rho = rho < floor ? floor : rho;
}

// value += increment, compensated (Kahan): `residual` keeps the low-order part the float sum lost,
// and gives it back in later additions, so that many increments far below value's resolution add up
// as they would in exact arithmetic (the temperature's, heat_transfer.hpp). Plain float arithmetic
// in this order (no -ffast-math, which would reassociate it away).
SPATE_HD void compensated_add(float& value, float& residual, float increment) {
  const float y = increment - residual;
  const float t = value + y;
  residual = (t - value) - y;
  value = t;
}

// The particle-shifting displacement (shifting.hpp), added after the corrector.
SPATE_HD void apply_shift(float& x, float shift) { x += shift; }

}  // namespace spate
