// Tait equation of state (eq. 9, solver/physics/eos.hpp) and its inverse.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/eos.hpp"

namespace spate {
namespace {

constexpr float kRho0 = 1000.0f;
constexpr float kC0 = 24.0f;
constexpr float kB = kC0 * kC0 * kRho0 / 7.0f;

TEST(Eos, ZeroPressureAtReferenceDensity) { EXPECT_EQ(tait_pressure(kRho0, kRho0, kB), 0.0f); }

TEST(Eos, Pow7IsTheSeventhPower) {
  for (float x : {0.0f, 0.5f, 0.99f, 1.0f, 1.01f, 1.3f, 2.0f})
    EXPECT_NEAR(pow7(x), std::pow(static_cast<double>(x), 7.0), 4e-7 * std::pow(static_cast<double>(x), 7.0)) << x;
}

TEST(Eos, GammaSevenAgainstDoublePrecision) {
  for (double ratio = 0.9; ratio <= 1.1001; ratio += 0.01) {
    const double expected = kB * (std::pow(ratio, 7.0) - 1.0);
    const float p = tait_pressure(static_cast<float>(kRho0 * ratio), kRho0, kB);
    // Float rounding of rho/rho0 is amplified 7 times in (rho/rho0)^7.
    EXPECT_NEAR(p, expected, 1e-5 * kB) << "rho/rho0 = " << ratio;
  }
}

TEST(Eos, LinearisedSlopeIsSoundSpeedSquared) {
  // dp/drho at rho0 is c0^2: 1% compression gives about 7% of B, i.e. c0^2 * 0.01 rho0.
  const float drho = 0.01f;
  const float p = tait_pressure(kRho0 + drho, kRho0, kB);
  EXPECT_NEAR(p / drho, kC0 * kC0, 1e-2 * kC0 * kC0);
}

TEST(Eos, StiffAndMonotone) {
  float previous = tait_pressure(0.5f * kRho0, kRho0, kB);
  EXPECT_NEAR(previous, kB * (std::pow(0.5, 7.0) - 1.0), 1e-6 * kB);  // tension bounded by -B
  for (int k = 1; k <= 100; ++k) {
    const float p = tait_pressure(kRho0 * (0.5f + 0.01f * k), kRho0, kB);
    EXPECT_GT(p, previous);
    previous = p;
  }
  // Gamma 7: doubling the density multiplies (p/B + 1) by 128.
  EXPECT_NEAR(tait_pressure(2.0f * kRho0, kRho0, kB) / kB + 1.0f, 128.0f, 1e-4f);
}

TEST(Eos, DensityInvertsPressure) {
  for (int k = 0; k <= 200; ++k) {
    const float rho = kRho0 * (0.9f + 0.001f * k);
    const float back = tait_density(tait_pressure(rho, kRho0, kB), kRho0, kB);
    EXPECT_NEAR(back, rho, 4.0f * std::numeric_limits<float>::epsilon() * rho) << rho;
  }
  EXPECT_EQ(tait_density(0.0f, kRho0, kB), kRho0);
}

TEST(Eos, HydrostaticInitialDensity) {
  // A particle 0.3 m under the surface: p = rho0 g d, and tait_density gives rho with that pressure.
  const float p = kRho0 * 9.81f * 0.3f;
  const float rho = tait_density(p, kRho0, kB);
  EXPECT_GT(rho, kRho0);
  EXPECT_NEAR(tait_pressure(rho, kRho0, kB), p, 1e-3f * p);
}

}  // namespace
}  // namespace spate
