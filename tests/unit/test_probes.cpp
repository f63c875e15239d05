// Probe pieces that need no simulation (sim/probes.cpp): the sensor's moving average and the points
// on which a wall-pressure sensor samples the fluid.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/probes.hpp"

namespace spate {
namespace {

TEST(MovingAverage, ZeroWindowPassesSamplesThrough) {
  MovingAverage a(0.0);
  EXPECT_DOUBLE_EQ(a.add(0.0, 3.0), 3.0);
  EXPECT_DOUBLE_EQ(a.add(0.1, -2.0), -2.0);
}

// The mean of the piecewise-linear signal over the trailing window: a ramp v = t averaged over w
// lags it by w/2; before a full window the mean covers what was sampled.
TEST(MovingAverage, RampLagsByHalfTheWindow) {
  MovingAverage a(0.01);
  double last = 0.0;
  for (int k = 0; k <= 100; ++k) {
    const double t = 1e-3 * k + 0.37e-3 * (k % 3);  // uneven sampling
    last = a.add(t, t);
    if (t > 0.0105) EXPECT_NEAR(last, t - 0.005, 1e-12) << t;
    if (k == 2) EXPECT_NEAR(last, 0.5 * (t - 0.0), 1e-12);
  }
  MovingAverage c(0.002);
  for (int k = 0; k < 50; ++k) EXPECT_DOUBLE_EQ(c.add(1e-4 * k, 7.5), 7.5);
}

// The sensor's points lie on its disc (segment in 2D), centred on its position, spaced at most dp/4.
TEST(SensorPoints, CoverTheDiscEvenly) {
  ProbeSpec s;
  s.position = {1.61, 0.003, 0};
  s.normal = {-1, 0, 0};
  s.diameter = 0.0042;
  const auto line = sensor_points(s, 2, 0.005);
  ASSERT_EQ(line.size(), 4u);  // ceil(4.2 / 1.25)
  double mean = 0;
  for (auto& x : line) {
    EXPECT_DOUBLE_EQ(x[0], 1.61);
    EXPECT_LE(std::fabs(x[1] - 0.003), 0.0021);
    mean += x[1] / line.size();
  }
  EXPECT_NEAR(mean, 0.003, 1e-12);
  s.position = {0.89, 0.305, 0.02};
  s.diameter = 0.01;
  const auto disc = sensor_points(s, 3, 0.01);
  ASSERT_GT(disc.size(), 8u);
  Vec3d centre{0, 0, 0};
  for (auto& x : disc) {
    EXPECT_DOUBLE_EQ(x[0], 0.89);
    EXPECT_LE(std::hypot(x[1] - 0.305, x[2] - 0.02), 0.005 + 1e-12);
    for (int k = 0; k < 3; ++k) centre[k] += x[k] / disc.size();
  }
  EXPECT_NEAR(centre[1], 0.305, 1e-12);
  EXPECT_NEAR(centre[2], 0.02, 1e-12);
  s.diameter = 0;
  EXPECT_EQ(sensor_points(s, 3, 0.01).size(), 1u);
}

}  // namespace
}  // namespace spate
