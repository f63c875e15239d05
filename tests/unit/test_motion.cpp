// Prescribed wall motions (case/motion.*, physics/wall_motion.hpp): the evaluation in time, the
// rigid maps the predictor applies, the rigid-body kinematics the pair terms see, steering, and
// what the case loader accepts.
#include <gtest/gtest.h>

#include "../source_dir.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>

#include "case/case.hpp"
#include "case/generator.hpp"
#include "sim/steering.hpp"

namespace spate {
namespace {

constexpr double kPiD = 3.14159265358979323846;

MotionSpec sway(double amplitude, double period, double ramp) {
  MotionSpec s;
  s.body = "tank";
  s.translation = {amplitude, 0, 0};
  s.omega = 2 * kPiD / period;
  s.ramp = ramp;
  return s;
}

// Central differences of the displacement and angle against the evaluated derivatives.
void expect_consistent_derivatives(const MotionSet& m, int k, double t) {
  const double e = 1e-5;
  const MotionSample a = m.sample(k, t - e), b = m.sample(k, t), c = m.sample(k, t + e);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR((c.displacement[i] - a.displacement[i]) / (2 * e), b.velocity[i], 1e-6) << "t " << t;
    EXPECT_NEAR((c.velocity[i] - a.velocity[i]) / (2 * e), b.acceleration[i], 1e-5) << "t " << t;
  }
  EXPECT_NEAR((c.angle - a.angle) / (2 * e), b.angular_velocity, 1e-6) << "t " << t;
  EXPECT_NEAR((c.angular_velocity - a.angular_velocity) / (2 * e), b.angular_acceleration, 1e-5) << "t " << t;
}

}  // namespace

TEST(MotionSet, SinusoidRampsUpSmoothlyThenFollowsTheSine) {
  MotionSpec s = sway(0.02, 1.2, 2.4);
  s.rotation = 0.1;
  const MotionSet m({s}, 2);
  EXPECT_EQ(m.sample(0, 0.0).displacement[0], 0.0);
  EXPECT_EQ(m.sample(0, 0.0).velocity[0], 0.0);  // a smooth start: no jump in velocity
  for (double t : {0.3, 1.0, 2.0, 2.39, 2.41, 5.0}) expect_consistent_derivatives(m, 0, t);
  for (double t : {2.4, 3.1, 7.7}) {
    EXPECT_NEAR(m.sample(0, t).displacement[0], 0.02 * std::sin(2 * kPiD / 1.2 * t), 1e-12);
    EXPECT_NEAR(m.sample(0, t).angle, 0.1 * std::sin(2 * kPiD / 1.2 * t), 1e-12);
  }
}

TEST(MotionSet, AnEndRampStopsTheMotionWithoutAJump) {
  MotionSpec s = sway(0.005, 1.5, 1.5);
  s.end = 6.0;
  s.end_ramp = 0.75;
  const MotionSet m({s}, 2);
  for (double t : {5.3, 5.6, 5.99}) expect_consistent_derivatives(m, 0, t);
  EXPECT_NEAR(m.sample(0, 5.999999).velocity[0], 0.0, 1e-9);
  const MotionSample after = m.sample(0, 6.5);
  EXPECT_EQ(after.displacement[0], 0.0);
  EXPECT_EQ(after.velocity[0], 0.0);
  EXPECT_EQ(after.acceleration[0], 0.0);
}

TEST(MotionSet, TimeSeriesIsAnInterpolatingSplineWithContinuousVelocity) {
  const auto file = std::filesystem::path(testing::TempDir()) / "spate_motion.csv";
  {
    std::ofstream out(file);
    out.precision(17);
    out << "time,x,angle\n";
    for (int i = 0; i <= 40; ++i) out << 0.05 * i << ',' << 0.01 * std::sin(2.0 * 0.05 * i) << ',' << 2.0 * 0.05 * i << '\n';
  }
  MotionSpec s;
  read_motion_csv(file.string(), s);
  ASSERT_EQ(s.times.size(), 41u);
  EXPECT_NEAR(s.values[10][3], 2.0 * 0.5 * kPiD / 180.0, 1e-15);  // degrees in the file
  const MotionSet m({s}, 2);
  EXPECT_NEAR(m.sample(0, 0.5).displacement[0], 0.01 * std::sin(1.0), 1e-15);  // through the samples
  EXPECT_NEAR(m.sample(0, 0.525).displacement[0], 0.01 * std::sin(1.05), 1e-7);  // a smooth curve between
  EXPECT_NEAR(m.sample(0, 0.525).velocity[0], 0.02 * std::cos(1.05), 1e-5);
  for (double t : {0.5, 0.52, 1.0, 1.51}) expect_consistent_derivatives(m, 0, t);
  EXPECT_EQ(m.sample(0, 5.0).displacement[0], m.sample(0, 2.0).displacement[0]);  // holds after the last time
  EXPECT_EQ(m.sample(0, 5.0).velocity[0], 0.0);
  // Bad files are refused with the line.
  std::ofstream(file) << "time,x\n0,0\n0,1\n";
  MotionSpec bad;
  try {
    read_motion_csv(file.string(), bad);
    ADD_FAILURE() << "decreasing times accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":3: times must increase"), std::string::npos) << e.what();
  }
}

// Applying the predictor's rigid maps step after step moves a point exactly as the closed form
// x(t) = c + d(t) + R(theta(t)) (x(0) - c) says, up to float rounding once per step.
TEST(MotionSet, StepsComposeToTheRigidMotion) {
  MotionSpec s = sway(0.03, 0.8, 0.4);
  s.translation[2] = 0.01;
  s.rotation = 0.2;
  s.axis = {0.0, 0.6, 0.8};
  s.centre = {0.5, 0.2, 0.1};
  const MotionSet m({s}, 3);
  const double x0[3] = {0.9, -0.1, 0.4};
  std::vector<float> x[3] = {{static_cast<float>(x0[0])}, {static_cast<float>(x0[1])}, {static_cast<float>(x0[2])}};
  PhysicsParams P;
  P.dim = 3;
  double t = 0.0;
  const double dt = 1.0e-3;
  for (int n = 0; n < 1500; ++n, t += dt) {
    m.set_step(P, t, t + dt);
    apply_motion_step(P.motion_step[0], 3, x, 0);
  }
  // Closed form at t.
  const MotionSample now = m.sample(0, t);
  const double c = std::cos(now.angle), sn = std::sin(now.angle), C = 1 - c;
  const double ax = s.axis[0], ay = s.axis[1], az = s.axis[2];
  const double R[3][3] = {{c + ax * ax * C, ax * ay * C - az * sn, ax * az * C + ay * sn},
                          {ay * ax * C + az * sn, c + ay * ay * C, ay * az * C - ax * sn},
                          {az * ax * C - ay * sn, az * ay * C + ax * sn, c + az * az * C}};
  for (int k = 0; k < 3; ++k) {
    double want = s.centre[k] + now.displacement[k];
    for (int l = 0; l < 3; ++l) want += R[k][l] * (x0[l] - s.centre[l]);
    EXPECT_NEAR(x[k][0], want, 2e-6) << "component " << k;
  }
}

// A wall particle's velocity and acceleration from the motion state are the time derivatives of
// its rigid path.
TEST(WallMotion, RigidKinematicsAreTheDerivativesOfThePath) {
  MotionSpec s = sway(0.01, 1.0, 0.0);
  s.rotation = 0.3;
  s.centre = {0.4, 0.1, 0};
  const MotionSet m({s}, 2);
  PhysicsParams P;
  P.dim = 2;
  const double t = 0.37, e = 1e-4;
  const Vec<2> x0{{0.9f, 0.45f}};
  auto path = [&](double time) {  // where the particle that starts at x0 is at `time`
    const MotionSample q = m.sample(0, time);
    const double dx = x0[0] - s.centre[0], dy = x0[1] - s.centre[1];
    return std::array<double, 2>{s.centre[0] + q.displacement[0] + std::cos(q.angle) * dx - std::sin(q.angle) * dy,
                                 s.centre[1] + q.displacement[1] + std::sin(q.angle) * dx + std::cos(q.angle) * dy};
  };
  const auto a = path(t - e), b = path(t), c = path(t + e);
  m.set_step(P, t, t);
  const Vec<2> xb{{static_cast<float>(b[0]), static_cast<float>(b[1])}};
  const Vec<2> v = rigid_velocity<2>(P.motion[0], xb), acc = rigid_acceleration<2>(P.motion[0], xb);
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(v[k], (c[k] - a[k]) / (2 * e), 2e-5) << k;
    EXPECT_NEAR(acc[k], (c[k] - 2 * b[k] + a[k]) / (e * e), 2e-3) << k;
  }
}

// Steering: a new amplitude scale blends in over one period; a new frequency keeps the phase
// continuous; neither makes the wall jump.
TEST(MotionSet, SteeringChangesAmplitudeAndFrequencyWithoutAJump) {
  MotionSet m({sway(0.01, 1.0, 0.0)}, 2);
  const double ts = 3.3;
  const MotionSample before = m.sample(0, ts);
  m.set_amplitude(0, 2.0, ts);
  const MotionSample at = m.sample(0, ts);
  EXPECT_NEAR(at.displacement[0], before.displacement[0], 1e-15);
  EXPECT_NEAR(at.velocity[0], before.velocity[0], 1e-12);
  for (double t : {3.35, 3.8, 4.29}) expect_consistent_derivatives(m, 0, t);
  EXPECT_NEAR(m.sample(0, 5.55).displacement[0], 0.02 * std::sin(2 * kPiD * 5.55), 1e-12);  // doubled after one period
  const MotionSample f0 = m.sample(0, 6.1);
  m.set_frequency(0, 0.5, 6.1);
  EXPECT_NEAR(m.sample(0, 6.1).displacement[0], f0.displacement[0], 1e-12);
  EXPECT_NEAR(m.frequency(0), 0.5, 1e-15);
  EXPECT_NEAR(m.sample(0, 6.1 + 2.0).displacement[0], f0.displacement[0], 1e-12);  // one new period later
  // What steering accepts.
  EXPECT_FALSE(m.check_amplitude(0, 0.0).has_value());
  EXPECT_TRUE(m.check_amplitude(0, 2.5).has_value());
  EXPECT_TRUE(m.check_amplitude(1, 1.0).has_value());
  EXPECT_TRUE(m.check_frequency(0, 0.0).has_value());
  EXPECT_FALSE(m.check_frequency(0, 3.0).has_value());
  SteeringChange c{10, 0.1, "motion_amplitude", {0, 1.5}};
  EXPECT_FALSE(validate(c, 2, &m).has_value());
  c.value = {0.5, 1.5};
  EXPECT_NE(validate(c, 2, &m).value_or("").find("whole number"), std::string::npos);
  c.value = {3, 1.5};
  EXPECT_NE(validate(c, 2, &m).value_or("").find("no motion 3"), std::string::npos);
  c.value = {0, 1.5};
  const MotionSet none;
  EXPECT_NE(validate(c, 2, &none).value_or("").find("no moving walls"), std::string::npos);
  // Without the case's motions (a recorded log read before the run): the ranges only.
  EXPECT_FALSE(validate(c, 2, nullptr).has_value());
  c.value = {0, 2.5};
  EXPECT_TRUE(validate(c, 2, nullptr).has_value());
  c = {10, 0.1, "motion_frequency", {0, 200}};
  EXPECT_NE(validate(c, 2, &m).value_or("").find("outside (0, 100]"), std::string::npos);
  c.value = {0};
  EXPECT_TRUE(validate(c, 2, &m).has_value());  // two values
}

TEST(CaseLoader, MotionsOfTheTankAndOfSolidsNameTheirMaterials) {
  const Case c = load_case(test::source_dir() + "/cases/wave_flume_2d.yaml");
  ASSERT_EQ(c.motions.size(), 1u);
  EXPECT_EQ(c.motions[0].body, "piston");
  EXPECT_EQ(c.solids[0].motion, 0);
  EXPECT_NEAR(c.motions[0].omega, 2 * kPiD / 1.2, 1e-12);
  const PhysicsParams P = physics_params(c);
  EXPECT_EQ(P.materials.motion[P.materials.solid(0)], 1);
  EXPECT_EQ(P.materials.motion[P.materials.tank()], 0);
  EXPECT_TRUE(P.moving_walls());
  // The lattice leaves room for the piston's widest stroke (steering may double it): the tank's
  // outer wall at -0.2 - 3 dp, less twice the 0.02 m amplitude, less one kernel support.
  const Lattice L = make_lattice(c);
  EXPECT_NEAR(L.origin[0], -0.26 - 2 * 0.02 - 2 * c.smoothing_ratio * 0.02 * 1.001, 1e-5);
  const Case slosh = load_case(test::source_dir() + "/cases/sloshing_2d.yaml");
  EXPECT_EQ(slosh.tank_motion, 0);
  EXPECT_EQ(physics_params(slosh).materials.motion[1], 1);
}

TEST(CaseLoader, BadMotionsAreRefusedWithTheKey) {
  const std::string file = test::source_dir() + "/cases/sloshing_2d.yaml";
  auto refuse = [&](std::vector<std::string> sets, const std::string& needle) {
    try {
      load_case(file, sets);
      ADD_FAILURE() << "accepted: " << sets.back();
    } catch (const CaseError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  refuse({"tank.motion.frequency=2"}, "'tank.motion.period'");
  refuse({"tank.motion.period=-1"}, "must be > 0");
  refuse({"tank.motion.translation=[0, 0]"}, "needs a translation or a rotation");
  refuse({"tank.motion.axis=[1, 0, 0]"}, "'tank.motion.axis'");
  refuse({"tank.motion.ramp=-1"}, "'tank.motion.ramp'");
  refuse({"tank.motion.end=1", "tank.motion.end_ramp=2"}, "'tank.motion.end_ramp'");
  refuse({"tank.motion.period=~", "tank.motion.translation=~", "tank.motion.file=no_such.csv"}, "cannot read the motion time series");
  refuse({"tank.motion.file=no_such.csv"}, "a time series (file) takes no 'period'");
  refuse({"tank.motion.speed=1"}, "unknown key");
  refuse({"tank.periodic=[x]"}, "no periodic axes with a motion");
  refuse({"tank.wall_shear=log_law"}, "not a box tank's faces");
  // The Riemann flux's wall term takes walls at rest; a sensor on a moving wall would stay behind.
  refuse({"momentum.flux=riemann"}, "'momentum.flux'");
  refuse({"probes=[{name: s, type: wall_pressure, position: [0.0, 0.05]}]"}, "on a moving wall is not supported");
  // In the flume a sensor on the moving piston is refused, one on the static far wall is fine.
  const std::string flume = test::source_dir() + "/cases/wave_flume_2d.yaml";
  EXPECT_THROW(load_case(flume, {"probes=[{name: s, type: wall_pressure, position: [0, 0.05]}]"}), CaseError);
  const Case far = load_case(flume, {"probes=[{name: s, type: wall_pressure, position: [10.0, 0.05]}]"});
  EXPECT_EQ(far.probes.at(0).type, ProbeType::WallPressure);
}

}  // namespace spate
