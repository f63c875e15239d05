// Tait equation of state (eq. 9, solver/physics/eos.hpp) and its inverse.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "physics/eos.hpp"

namespace spate {
namespace {

constexpr float kRho0 = 1000.0f;
constexpr float kC0 = 24.0f;
constexpr float kB = kC0 * kC0 * kRho0 / 7.0f;
const FluidMaterial kWater = make_fluid(kRho0, kC0, 7.0f, 1.0e-3f, 1.0f);

TEST(Eos, ZeroPressureAtReferenceDensity) { EXPECT_EQ(tait_pressure(kRho0, kWater), 0.0f); }

TEST(Eos, Pow7IsTheSeventhPower) {
  for (float x : {0.0f, 0.5f, 0.99f, 1.0f, 1.01f, 1.3f, 2.0f})
    EXPECT_NEAR(pow7(x), std::pow(static_cast<double>(x), 7.0), 4e-7 * std::pow(static_cast<double>(x), 7.0)) << x;
}

TEST(Eos, SeventhRootIsCorrectlyRoundedFromPlainArithmetic) {
  // The wall state's inverse EOS takes x^(1/7) from + - * / alone, so that the CPU and the GPU
  // round it alike (powf's last bit is the library's); it must still be the correctly rounded
  // root: within half an ulp of double precision's over twelve decades.
  double worst = 0.0;
  for (float x = 1e-6f; x < 1e6f; x *= 1.0001f) {
    const double exact = std::pow(static_cast<double>(x), 1.0 / 7.0);
    const float r = static_cast<float>(exact);
    const double ulp = std::nextafter(r, INFINITY) - r;
    worst = std::max(worst, std::fabs(seventh_root(x) - exact) / ulp);
  }
  EXPECT_LE(worst, 0.5 + 1e-6);
  EXPECT_EQ(seventh_root(1.0f), 1.0f);
  EXPECT_EQ(seventh_root(128.0f), 2.0f);
  EXPECT_EQ(seventh_root(0.0f), 0.0f);
  EXPECT_TRUE(std::isnan(seventh_root(-1.0f)));
  EXPECT_TRUE(std::isnan(seventh_root(NAN)));
  EXPECT_TRUE(std::isnan(seventh_root(-INFINITY)));
  EXPECT_TRUE(std::signbit(seventh_root(-0.0f)));
  EXPECT_EQ(seventh_root(INFINITY), INFINITY);
}

TEST(Eos, PortableWallDensityTakesTheSeventhRoot) {
  // fluid.portable_eos: the inverse EOS by seventh_root, within an ulp of powf's; other exponents
  // keep powf.
  for (float p : {-1000.0f, 0.0f, 5.0e3f, 4.0e4f, 3.0e5f}) {
    const float x = p / kWater.tait_b + 1.0f;
    EXPECT_EQ(tait_density(p, kWater, true), kRho0 * seventh_root(x)) << p;
    EXPECT_NEAR(tait_density(p, kWater, true), tait_density(p, kWater), 2e-7f * kRho0 * seventh_root(x)) << p;
  }
  const FluidMaterial air = make_fluid(1.2f, 30.0f, 1.4f, 1.8e-5f, 1.0f);
  EXPECT_EQ(tait_density(200.0f, air, true), tait_density(200.0f, air));
}

TEST(Eos, GammaSevenAgainstDoublePrecision) {
  for (double ratio = 0.9; ratio <= 1.1001; ratio += 0.01) {
    const double expected = kB * (std::pow(ratio, 7.0) - 1.0);
    const float p = tait_pressure(static_cast<float>(kRho0 * ratio), kWater);
    // Float rounding of rho/rho0 is amplified 7 times in (rho/rho0)^7.
    EXPECT_NEAR(p, expected, 1e-5 * kB) << "rho/rho0 = " << ratio;
  }
}

TEST(Eos, LinearisedSlopeIsSoundSpeedSquared) {
  // dp/drho at rho0 is c0^2: 1% compression gives about 7% of B, i.e. c0^2 * 0.01 rho0.
  const float drho = 0.01f;
  const float p = tait_pressure(kRho0 + drho, kWater);
  EXPECT_NEAR(p / drho, kC0 * kC0, 1e-2 * kC0 * kC0);
}

TEST(Eos, StiffAndMonotone) {
  float previous = tait_pressure(0.5f * kRho0, kWater);
  EXPECT_NEAR(previous, kB * (std::pow(0.5, 7.0) - 1.0), 1e-6 * kB);  // tension bounded by -B
  for (int k = 1; k <= 100; ++k) {
    const float p = tait_pressure(kRho0 * (0.5f + 0.01f * k), kWater);
    EXPECT_GT(p, previous);
    previous = p;
  }
  // Gamma 7: doubling the density multiplies (p/B + 1) by 128.
  EXPECT_NEAR(tait_pressure(2.0f * kRho0, kWater) / kB + 1.0f, 128.0f, 1e-4f);
}

TEST(Eos, DensityInvertsPressure) {
  for (int k = 0; k <= 200; ++k) {
    const float rho = kRho0 * (0.9f + 0.001f * k);
    const float back = tait_density(tait_pressure(rho, kWater), kWater);
    EXPECT_NEAR(back, rho, 4.0f * std::numeric_limits<float>::epsilon() * rho) << rho;
  }
  EXPECT_EQ(tait_density(0.0f, kWater), kRho0);
}

TEST(Eos, HydrostaticInitialDensity) {
  // A particle 0.3 m under the surface: p = rho0 g d, and tait_density gives rho with that pressure.
  const float p = kRho0 * 9.81f * 0.3f;
  const float rho = tait_density(p, kWater);
  EXPECT_GT(rho, kRho0);
  EXPECT_NEAR(tait_pressure(rho, kWater), p, 1e-3f * p);
}

TEST(Eos, MaterialDerivesTaitCoefficientAsBefore) {
  EXPECT_EQ(kWater.tait_b, kB);  // c0^2 rho0 / gamma, rounded as always
  EXPECT_EQ(kWater.inv_gamma, 1.0f / 7.0f);
}

// The Tait exponent of the material is honoured (gamma = 7 takes the exact product; any other
// value pow), and the background pressure is added to the pressure and removed by the inverse.
TEST(Eos, TaitExponentAndBackgroundPressureHonoured) {
  for (float gamma : {1.0f, 1.4f, 3.0f, 7.0f}) {
    const FluidMaterial air = make_fluid(1.2f, 30.0f, gamma, 1.8e-5f, 1.0f, 250.0f);
    EXPECT_EQ(tait_pressure(air.rho0, air), air.background_pressure) << gamma;
    for (double ratio = 0.8; ratio <= 1.2001; ratio += 0.05) {
      const double expected = air.tait_b * (std::pow(ratio, static_cast<double>(gamma)) - 1.0) + 250.0;
      const float rho = static_cast<float>(air.rho0 * ratio);
      EXPECT_NEAR(tait_pressure(rho, air), expected, 2e-5 * air.tait_b * gamma) << "gamma " << gamma << ", ratio " << ratio;
      EXPECT_NEAR(tait_density(tait_pressure(rho, air), air), rho, 1e-5f * rho) << "gamma " << gamma;
    }
  }
  // The sound speed ratio of the Fourtakas term: (rho/rho0)^(gamma - 1), exact product for 7.
  const float s = 1.1f, s2 = s * s;
  EXPECT_EQ(tait_sound_speed_ratio2<true>(s, 7.0f), s2 * s2 * s2);
  EXPECT_NEAR(tait_sound_speed_ratio2<false>(1.1f, 7.0f), tait_sound_speed_ratio2<true>(1.1f, 7.0f), 1e-6f);
  EXPECT_NEAR(tait_sound_speed_ratio2<false>(1.1f, 1.4f), std::pow(1.1, 0.4), 1e-6);
}

}  // namespace
}  // namespace spate
