// The growth-rate fit shared by `spate growth`, the Rayleigh-Taylor validation test and the docs
// (solver/sim/growth.hpp), and the viscous linear theory it is compared with.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "sim/growth.hpp"

namespace spate {
namespace {

// a0 cosh(n t) plus a slower viscous decaying mode: the fit recovers n, and stops where the
// amplitude first exceeds `until` (a nonlinear tail beyond it would bend the fit).
TEST(GrowthFit, RecoversTheRateOfAGrowingAndADecayingMode) {
  std::vector<std::pair<double, double>> s;
  for (int k = 0; k <= 150; ++k) {
    const double t = 0.02 * k;
    const double linear = 0.004 * std::exp(1.2 * t) + 0.0035 * std::exp(-1.2 * t);
    s.emplace_back(t, linear > 0.03 ? 0.03 + 0.2 * (linear - 0.03) : linear);  // saturates past 0.03
  }
  const GrowthFit fit = fit_growth(s, 0.03);
  EXPECT_NEAR(fit.rate, 1.2, 1e-6);
  EXPECT_NEAR(fit.growing, 0.004, 1e-8);
  EXPECT_NEAR(fit.decaying, 0.0035, 1e-8);
  EXPECT_LT(fit.to, 1.7) << "the fit must stop before the saturated tail";
  EXPECT_LT(fit.rms, 1e-9);
  EXPECT_THROW(fit_growth({{0, 0.01}, {0.1, 0.02}, {0.2, 0.05}}, 1.0), std::invalid_argument);
}

// Rayleigh-Taylor of rayleigh_taylor_linear_2d.yaml: A = 0.8/2.8, k = 2 pi, nu = 1/420.
TEST(GrowthFit, ViscousRayleighTaylorRate) {
  EXPECT_NEAR(rayleigh_taylor_rate(0.8 / 2.8, 1.0, 2 * M_PI, 1.0 / 420), 1.2492, 1e-4);
  EXPECT_DOUBLE_EQ(rayleigh_taylor_rate(0.5, 2.0, 3.0, 0.0), std::sqrt(3.0));  // inviscid: sqrt(A g k)
}

TEST(GrowthFit, ReadsAProbeColumnByName) {
  const std::string csv = ::testing::TempDir() + "spate_growth_probe.csv";
  std::ofstream(csv) << "time[s],step,amplitude[m],top[m],bottom[m]\n0,0,0.0075,0.5075,0.4925\n0.5,10,0.009,0.509,0.491\n";
  const auto a = read_probe_column(csv, "amplitude");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_DOUBLE_EQ(a[1].first, 0.5);
  EXPECT_DOUBLE_EQ(a[1].second, 0.009);
  try {
    read_probe_column(csv, "height");
    FAIL() << "an unknown column must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no column 'height' (columns: amplitude, top, bottom)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace spate
