// The velocity-Verlet integrator (solver/physics/integrator.hpp) on one particle under gravity:
// with a constant acceleration it is exact, so positions follow x0 + v0 t + g t^2 / 2 up to float
// rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "physics/integrator.hpp"

namespace spate {
namespace {

struct Ballistic {
  float x[3], v[3], a_prev[3];
  float rho, rho_rate_prev;
};

// One step as the drivers sequence it: predict, evaluate (constant gravity; no density rate), correct.
void step(Ballistic& p, const float g[3], float dt) {
  for (int k = 0; k < 3; ++k) predict_component(p.x[k], p.v[k], p.a_prev[k], dt);
  predict_density(p.rho, p.rho_rate_prev, dt);
  for (int k = 0; k < 3; ++k) {
    const float a_new = g[k];
    correct(p.v[k], a_new, p.a_prev[k], dt);
    p.a_prev[k] = a_new;
  }
  correct(p.rho, 0.0f, p.rho_rate_prev, dt);
  p.rho_rate_prev = 0.0f;
}

TEST(Integrator, FreeFallFollowsTheParabola) {
  const float g[3] = {0.0f, 0.0f, -9.81f};
  const double x0[3] = {0.1, 0.2, 1.0};
  const double v0[3] = {0.5, -0.25, 2.0};
  Ballistic p{};
  for (int k = 0; k < 3; ++k) {
    p.x[k] = static_cast<float>(x0[k]);
    p.v[k] = static_cast<float>(v0[k]);
    p.a_prev[k] = g[k];  // a fresh start computes rates before the first step
  }
  p.rho = 1000.0f;
  const float dt = 1.0e-3f;
  const int steps = 500;
  const double eps = std::numeric_limits<float>::epsilon();
  for (int n = 1; n <= steps; ++n) {
    step(p, g, dt);
    const double t = n * static_cast<double>(dt);
    for (int k = 0; k < 3; ++k) {
      const double x = x0[k] + v0[k] * t + 0.5 * g[k] * t * t;
      const double v = v0[k] + g[k] * t;
      // Each step adds at most a few float roundings of the running position and velocity.
      const double x_scale = std::fabs(x0[k]) + std::fabs(v0[k]) * t + std::fabs(g[k]) * t * t + 1e-3;
      const double v_scale = std::fabs(v0[k]) + std::fabs(g[k]) * t;
      EXPECT_NEAR(p.x[k], x, 2.0 * n * eps * x_scale) << "step " << n << " axis " << k;
      EXPECT_NEAR(p.v[k], v, 2.0 * n * eps * v_scale + 1e-12) << "step " << n << " axis " << k;
    }
  }
  EXPECT_EQ(p.rho, 1000.0f);  // no density rate, no change
  // The drift at the end is far below what a first-order (Euler) step would give: dt g t / 2.
  const double t_end = steps * static_cast<double>(dt);
  const double exact_z = x0[2] + v0[2] * t_end + 0.5 * g[2] * t_end * t_end;
  EXPECT_LT(std::fabs(p.x[2] - exact_z), 1e-2 * 0.5 * dt * std::fabs(g[2]) * t_end);
}

TEST(Integrator, TrapezoidalKickAveragesOldAndNewRates) {
  // v^{n+1} = v^n + dt/2 (a^n + a^{n+1}) and rho^{n+1} = rho^n + dt/2 (D^n + D^{n+1}).
  float x = 0.0f, v = 1.0f;
  const float dt = 0.25f, a_old = 2.0f, a_new = 6.0f;
  predict_component(x, v, a_old, dt);
  EXPECT_FLOAT_EQ(x, 0.25f + 0.5f * 0.0625f * 2.0f);
  EXPECT_FLOAT_EQ(v, 1.5f);
  correct(v, a_new, a_old, dt);
  EXPECT_FLOAT_EQ(v, 1.0f + 0.5f * dt * (a_old + a_new));
  float rho = 1000.0f;
  predict_density(rho, 4.0f, dt);
  EXPECT_FLOAT_EQ(rho, 1001.0f);
  correct(rho, -4.0f, 4.0f, dt);
  EXPECT_FLOAT_EQ(rho, 1000.0f);
}

}  // namespace
}  // namespace spate
