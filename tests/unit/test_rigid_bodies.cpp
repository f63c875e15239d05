// Floating solids (sim/rigid_bodies.*, sim/multibody.*; issue 32): the rigid-body dynamics against
// closed-form motions under constant loads, locked degrees of freedom, the rigid map the kernels
// get, checkpoint round trips, mass properties, and what the case loader accepts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "case/case.hpp"
#include "case_errors.hpp"
#include "physics/params.hpp"
#include "sim/rigid_bodies.hpp"
#include "sim/steering.hpp"

namespace spate {
namespace {

// A 2D tank with one floating box (0.2 x 0.1 m, centre (0.6, 0.29)) and `extra` lines in its motion.
std::string case_2d(const std::string& keys = "density: 500", const std::string& solid_shape = "") {
  return "name: t\ndimensions: 2\ndp: 0.01\ngravity: [0, -9.81]\ntime: {end: 1}\ntank: {origin: [0, 0], size: [1.2, 0.5]}\n"
         "fluid_blocks: [{min: [0, 0], max: [0.4, 0.3]}]\n"
         "solids:\n  - name: box\n    " +
         (solid_shape.empty() ? std::string("min: [0.5, 0.24]\n    max: [0.7, 0.34]") : solid_shape) + "\n    motion: floating\n    " + keys + "\n";
}

std::string case_3d(const std::string& keys = "density: 500") {
  return "name: t\ndimensions: 3\ndp: 0.02\ngravity: [0, 0, -9.81]\ntime: {end: 1}\ntank: {origin: [0, 0, 0], size: [1, 1, 1]}\n"
         "fluid_blocks: [{min: [0, 0, 0], max: [0.3, 1, 0.3]}]\n"
         "solids:\n  - name: box\n    min: [0.4, 0.4, 0.4]\n    max: [0.6, 0.5, 0.7]\n    motion: floating\n    " + keys + "\n";
}

void run_steps(RigidBodies& b, int steps, double dt) {
  for (int k = 0; k < steps; ++k) b.advance(k * dt, (k + 1) * dt);
}

TEST(RigidBodies, ABoxGetsItsMassCentreAndInertiaFromItsDensity) {
  const Case c = parse_case(case_2d(), "case.yaml");
  ASSERT_EQ(c.bodies.size(), 1u);
  const BodySpec& b = c.bodies[0];
  EXPECT_DOUBLE_EQ(b.mass, 10.0);  // 500 kg/m3 x 0.02 m2
  EXPECT_NEAR(b.centre_of_mass[0], 0.6, 1e-12);
  EXPECT_NEAR(b.centre_of_mass[1], 0.29, 1e-12);
  EXPECT_NEAR(b.inertia[2], 10.0 * (0.04 + 0.01) / 12.0, 1e-12);
  EXPECT_EQ(c.motions[0].floating, 0);
  EXPECT_FALSE(c.motions[0].sinusoid());
  // The same rectangle as a polygon: the inertia by sampling, within 0.1%.
  const Case p = parse_case(case_2d("mass: 10", "polygon: [[0.5, 0.24], [0.7, 0.24], [0.7, 0.34], [0.5, 0.34]]"), "c.yaml");
  EXPECT_NEAR(p.bodies[0].mass, 10.0, 1e-9);
  EXPECT_NEAR(p.bodies[0].centre_of_mass[1], 0.29, 1e-9);
  EXPECT_NEAR(p.bodies[0].inertia[2], b.inertia[2], 1e-3 * b.inertia[2]);
  // A 3D box: Ixx = m (b^2 + c^2) / 12.
  const Case d = parse_case(case_3d(), "case.yaml");
  EXPECT_NEAR(d.bodies[0].mass, 500.0 * 0.2 * 0.1 * 0.3, 1e-12);
  EXPECT_NEAR(d.bodies[0].inertia[0], d.bodies[0].mass * (0.01 + 0.09) / 12.0, 1e-12);
  EXPECT_NEAR(d.bodies[0].inertia[2], d.bodies[0].mass * (0.04 + 0.01) / 12.0, 1e-12);
}

TEST(RigidBodies, AFreeBodyFallsAndTurnsAsNewtonSays) {
  const Case c = parse_case(case_2d("density: 500\n    contact: false"), "case.yaml");
  RigidBodies b(c);
  const double m = c.bodies[0].mass, I = c.bodies[0].inertia[2];
  BodyLoad l;
  l.force = {2.0, 50.0, 0.0};
  l.torque = {0.0, 0.0, 0.01};
  b.set_loads({l});
  run_steps(b, 100, 0.01);  // to t = 1 s
  const BodyState& s = b.state(0);
  const double ax = 2.0 / m, ay = 50.0 / m - 9.81, alpha = 0.01 / I;
  EXPECT_NEAR(s.centre[0], 0.6 + 0.5 * ax, 1e-9);
  EXPECT_NEAR(s.centre[1], 0.29 + 0.5 * ay, 1e-9);
  EXPECT_NEAR(s.velocity[1], ay, 1e-9);
  EXPECT_NEAR(s.acceleration[1], ay, 1e-9);
  EXPECT_NEAR(s.angles[2], 0.5 * alpha, 1e-9);
  EXPECT_NEAR(s.angular_velocity[2], alpha, 1e-9);
  EXPECT_NEAR(s.rotation[1][0], std::sin(0.5 * alpha), 1e-9);
}

TEST(RigidBodies, LockedDegreesOfFreedomStayPut) {
  const Case c = parse_case(case_2d("density: 500\n    free: [y]"), "case.yaml");
  EXPECT_FALSE(c.bodies[0].free[0]);
  EXPECT_TRUE(c.bodies[0].free[1]);
  EXPECT_FALSE(c.bodies[0].free[5]);
  RigidBodies b(c);
  BodyLoad l;
  l.force = {5.0, 120.0, 0.0};
  l.torque = {0.0, 0.0, 0.3};
  b.set_loads({l});
  run_steps(b, 50, 0.01);
  const BodyState& s = b.state(0);
  EXPECT_EQ(s.centre[0], 0.6);
  EXPECT_EQ(s.angles[2], 0.0);
  EXPECT_NEAR(s.centre[1], 0.29 + 0.5 * (120.0 / 10.0 - 9.81) * 0.25, 1e-9);
}

TEST(RigidBodies, TheKernelsGetTheStepsRigidMapAndTheStateAtItsEnd) {
  const Case c = parse_case(case_3d(), "case.yaml");
  RigidBodies b(c);
  BodyLoad l;
  l.force = {1.0, 0.0, 0.0};
  l.torque = {0.0, 0.0, 0.05};
  b.set_loads({l});
  run_steps(b, 20, 0.01);
  const BodyState before = b.state(0);
  b.advance(0.2, 0.21);
  const BodyState& now = b.state(0);
  PhysicsParams P;
  b.set_step(P);
  const MotionStep& st = P.motion_step[b.slot(0)];
  // A point fixed in the body: x(t) = c(t) + R(t) r. The map sends x(t0) to x(t1).
  const double r[3] = {0.05, -0.02, 0.1};
  double x0[3], x1[3], mapped[3];
  for (int i = 0; i < 3; ++i) {
    x0[i] = before.centre[i], x1[i] = now.centre[i];
    for (int j = 0; j < 3; ++j) x0[i] += before.rotation[i][j] * r[j], x1[i] += now.rotation[i][j] * r[j];
  }
  for (int i = 0; i < 3; ++i) {
    mapped[i] = st.to[i];
    for (int j = 0; j < 3; ++j) mapped[i] += st.rotation[i][j] * (x0[j] - st.from[j]);
    EXPECT_NEAR(mapped[i], x1[i], 1e-12);
  }
  EXPECT_FLOAT_EQ(P.motion[0].velocity[0], static_cast<float>(now.velocity[0]));
  EXPECT_FLOAT_EQ(P.motion[0].angular_velocity[2], static_cast<float>(now.angular_velocity[2]));
  EXPECT_GT(now.angular_velocity[2], 0.0);
}

TEST(RigidBodies, ARestoredStateContinuesBitForBit) {
  const Case c = parse_case(case_3d(), "case.yaml");
  RigidBodies a(c), b(c);
  BodyLoad l;
  l.force = {1.0, -3.0, 20.0};
  l.torque = {0.01, 0.02, 0.03};
  a.set_loads({l});
  run_steps(a, 10, 0.003);
  b.restore(a.save());
  a.advance(0.03, 0.033);
  b.advance(0.03, 0.033);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(a.state(0).centre[k], b.state(0).centre[k]);
    EXPECT_EQ(a.state(0).angular_velocity[k], b.state(0).angular_velocity[k]);
  }
  EXPECT_EQ(a.save(), b.save());
  // Resting on the floor (in contact from its first step, as after a restart): restored, it goes
  // on bit for bit.
  const Case floor = parse_case(case_2d("density: 500", "min: [0.5, 0.0]\n    max: [0.7, 0.1]"), "case.yaml");
  RigidBodies f(floor), g(floor);
  f.set_loads({BodyLoad{}});
  run_steps(f, 50, 2e-4);
  EXPECT_NEAR(f.state(0).centre[1], 0.05, 0.01 * floor.dp);
  g.restore(f.save());
  f.advance(0.01, 0.0102);
  g.advance(0.01, 0.0102);
  EXPECT_EQ(f.save(), g.save());
  EXPECT_THROW(b.restore(""), std::runtime_error);
  EXPECT_THROW(b.restore("other q 1 u 2 load 0 0 0 0 0 0\n"), std::runtime_error);
  EXPECT_THROW(b.restore("box q 1 2 u 3 load 0 0 0 0 0 0\n"), std::runtime_error);
}

// A hinge at the centre of mass with a rotational spring k: under a constant torque tau the angle
// goes (tau / k)(1 - cos(w t)), w = sqrt(k / I); at half a period it is 2 tau / k.
TEST(RigidBodies, AHingedBodyWithASpringSwingsAtItsNaturalFrequency) {
  const Case c = parse_case(case_2d("density: 500\n    hinge: {point: [0.6, 0.29], stiffness: 2.0, damping: 0}"), "case.yaml");
  ASSERT_TRUE(c.bodies[0].hinge.on);
  RigidBodies b(c);
  const double I = c.bodies[0].inertia[2], k = 2.0, tau = 0.05, w = std::sqrt(k / I);
  BodyLoad l;
  l.force = {30.0, 80.0, 0.0};  // the hinge holds any force
  l.torque = {0.0, 0.0, tau};
  b.set_loads({l});
  const int n = 400;
  const double half = 3.14159265358979323846 / w, dt = half / n;
  run_steps(b, n, dt);
  EXPECT_NEAR(b.state(0).angles[2], 2 * tau / k, 1e-6);
  EXPECT_NEAR(b.state(0).centre[0], 0.6, 1e-12);
  EXPECT_NEAR(b.state(0).centre[1], 0.29, 1e-12);
  // A pendulum: the same body hinged 5 cm above its centre of mass (on its top face), set swinging
  // by a small torque over 1 ms: a quarter of its period 2 pi sqrt(I_h / (m g d)) later it turns.
  const Case p = parse_case(case_2d("density: 500\n    hinge: {point: [0.6, 0.34]}"), "case.yaml");
  RigidBodies q(p);
  const double m = p.bodies[0].mass, d = 0.05, Ih = p.bodies[0].inertia[2] + m * d * d, wp = std::sqrt(m * 9.81 * d / Ih);
  BodyLoad kick;
  kick.torque = {0.0, 0.0, 0.002};
  q.set_loads({kick});
  run_steps(q, 1, 1e-3);  // a small angular impulse, then free swinging
  q.set_loads({BodyLoad{}});
  const double omega0 = q.state(0).angular_velocity[2];
  const double quarter = 0.5 * 3.14159265358979323846 / wp;
  for (int k2 = 0; k2 < 200; ++k2) q.advance(1e-3 + k2 * quarter / 200, 1e-3 + (k2 + 1) * quarter / 200);
  // A quarter period after the kick (which lasted 1 ms) the swing turns: its speed is near zero.
  EXPECT_LT(std::fabs(q.state(0).angular_velocity[2]), 0.02 * std::fabs(omega0));
  EXPECT_GT(q.state(0).angles[2], 0.0);
}

// A heaving body on a vertical spring to an anchor above, at its natural length at rest: gravity
// pulls it down by (m g / k)(1 - cos(w t)). A slack line (a mooring) longer than the distance does
// nothing until taut: the body falls freely.
TEST(RigidBodies, SpringsPullAndSlackLinesOnlyWhenTaut) {
  const std::string keys = "density: 500\n    free: [y]\n    contact: false\n    springs: [{point: [0.6, 0.34], anchor: [0.6, 0.5], stiffness: 400}]";
  const Case c = parse_case(case_2d(keys), "case.yaml");
  ASSERT_EQ(c.bodies[0].springs.size(), 1u);
  EXPECT_NEAR(c.bodies[0].springs[0].length, 0.16, 1e-12);
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  const double m = c.bodies[0].mass, k = 400.0, w = std::sqrt(k / m), half = 3.14159265358979323846 / w;
  run_steps(b, 400, half / 400);
  EXPECT_NEAR(b.state(0).centre[1], 0.29 - 2 * m * 9.81 / k, 1e-6);
  const Case s = parse_case(case_2d("density: 500\n    free: [y]\n    springs: [{point: [0.6, 0.34], anchor: [0.6, 0.5], stiffness: 400, "
                                    "length: 0.3, slack: true}]"),
                            "case.yaml");
  RigidBodies f(s);
  f.set_loads({BodyLoad{}});
  run_steps(f, 100, 1e-3);  // 0.1 s: falls 4.9 cm, the line (0.16 m long now, 0.3 m slack) stays slack
  EXPECT_NEAR(f.state(0).centre[1], 0.29 - 0.5 * 9.81 * 0.01, 1e-9);
}

std::string test_sinking() {
  std::string c = case_2d();
  c.replace(c.find("motion: floating"), 16, "motion: sinking");
  return c;
}

// Contact with the tank (Simbody's compliant contact): the box dropped 0.24 m onto the floor hits
// it at 2.2 m/s, and neither passes through it (its corners at most dp/2 into it) nor bounces off
// for good: it comes to rest on the contact spheres (radius dp/100) at its two lower corners, each
// sunk by Hertz's x = penetration (1/2)^(2/3) under half its weight, level.
TEST(RigidBodies, ABoxDroppedOnTheFloorComesToRestOnIt) {
  const Case c = parse_case(case_2d(), "case.yaml");
  ASSERT_TRUE(c.bodies[0].contact.on);
  const double penetration = c.bodies[0].contact.penetration;
  EXPECT_DOUBLE_EQ(penetration, 0.01 * c.dp);
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  double lowest = 1.0, mean = 0.0, low = 1.0, high = 0.0;
  const double dt = 2e-4;
  for (int k = 0; k < 12500; ++k) {  // 2.5 s; the last 0.25 s averaged
    b.advance(k * dt, (k + 1) * dt);
    const double y = b.state(0).centre[1];
    lowest = std::min(lowest, y - 0.05);
    if (k >= 11250) mean += y / 1250, low = std::min(low, y), high = std::max(high, y);
  }
  EXPECT_GT(lowest, -0.5 * c.dp);
  EXPECT_LT(lowest, -penetration);  // it did reach the floor
  // It bounces for about 1.5 s (restitution about 0.4 at 2 m/s; in water the water damps it),
  // then rests but for a faint ringing on the contact's stiffness (Hunt & Crossley's damping fades
  // with the depth and speed).
  EXPECT_NEAR(mean, 0.05 + 0.01 * c.dp - penetration * std::pow(0.5, 2.0 / 3.0), 0.1 * penetration);
  EXPECT_LT(high - low, 0.3 * penetration);
  const BodyState& s = b.state(0);
  EXPECT_NEAR(s.centre[0], 0.6, 1e-6);
  EXPECT_NEAR(s.angles[2], 0.0, 1e-6);
}

// The mean and the spread of body b's centre height over the last `tail` of `steps` steps of dt.
struct Settled {
  double mean = 0.0, low = 1e9, high = -1e9, lowest = 1e9;
};
Settled settle(RigidBodies& b, int body, int steps, int tail, double dt, double bottom_offset) {
  Settled s;
  for (int k = 0; k < steps; ++k) {
    b.advance(k * dt, (k + 1) * dt);
    const double y = b.state(body).centre[1];
    s.lowest = std::min(s.lowest, y - bottom_offset);
    if (k >= steps - tail) s.mean += y / tail, s.low = std::min(s.low, y), s.high = std::max(s.high, y);
  }
  return s;
}

// Contact with a static solid (ShapeContacts in multibody.cpp): the box dropped 0.1 m onto a shelf
// (a static box solid, top at y = 0.14) neither passes into it (its corners at most dp/2 deep)
// nor bounces off for good: it rests on its two lower corners on the shelf as on the floor, each
// sunk by penetration (1/2)^(2/3), level and in place.
TEST(RigidBodies, ABoxDroppedOnAStaticSolidComesToRestOnIt) {
  const Case c = parse_case(case_2d() + "  - name: shelf\n    min: [0.45, 0.1]\n    max: [0.75, 0.14]\n", "case.yaml");
  ASSERT_EQ(c.solids.size(), 2u);
  const double penetration = c.bodies[0].contact.penetration, radius = 0.01 * c.dp;
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  const Settled s = settle(b, 0, 10000, 1000, 2e-4, 0.05 + 0.14);
  EXPECT_GT(s.lowest, -0.5 * c.dp);
  EXPECT_LT(s.lowest, -penetration);  // it did reach the shelf
  EXPECT_NEAR(s.mean, 0.14 + 0.05 + radius - penetration * std::pow(0.5, 2.0 / 3.0), 0.1 * penetration);
  EXPECT_LT(s.high - s.low, 0.3 * penetration);
  EXPECT_NEAR(b.state(0).centre[0], 0.6, 1e-6);
  EXPECT_NEAR(b.state(0).angles[2], 0.0, 1e-6);
}

// A solid's corner under a body's face (ShapeContacts, the solids' corners): the box (0.2 m wide,
// x = 0.5 to 0.7) let down from 1 mm onto a shelf that ends at x = 0.65 rests level on it, on its
// own left corner and the shelf's right corner under its bottom face, which carry W/3 and 2W/3
// (moments about its centre of mass at x = 0.6). Without the shelf's corners it tips about its
// left corner and its right half sinks through the shelf's edge.
TEST(RigidBodies, ABoxAcrossAShelfsEdgeRestsLevelOnIt) {
  const Case c = parse_case(case_2d() + "  - name: shelf\n    min: [0.45, 0.1]\n    max: [0.65, 0.239]\n", "case.yaml");
  const double penetration = c.bodies[0].contact.penetration, radius = 0.01 * c.dp, top = 0.239;
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  const Settled s = settle(b, 0, 10000, 1000, 2e-4, 0.05 + top);
  EXPECT_GT(s.lowest, -0.1 * c.dp);
  const BodyState& st = b.state(0);
  // Both supports sink as their loads say (Hertz: x ~ f^(2/3)); the box tilts by their difference
  // over the 0.15 m between them.
  const double left = penetration * std::pow(1.0 / 3.0, 2.0 / 3.0), right = penetration * std::pow(2.0 / 3.0, 2.0 / 3.0);
  const double tilt = (right - left) / 0.15;  // clockwise: a negative angle
  std::printf("box across the edge: centre (%.6f, %.6f) m, angle %.3g rad (the supports' sinking: %.3g rad)\n", st.centre[0], st.centre[1],
              st.angles[2], -tilt);
  EXPECT_NEAR(st.angles[2], -tilt, 0.2 * tilt);
  EXPECT_NEAR(s.mean, top + 0.05 + radius - (left + 0.1 / 0.15 * (right - left)), 0.1 * penetration);
  EXPECT_NEAR(st.centre[0], 0.6, 1e-3);
}

// An edge across a face (3D; the bodies' edge spheres): a plank (0.4 x 0.1 x 0.05 m) let down from
// 1 mm onto a static beam 0.1 m wide that spans the tank across it. None of the plank's corners is
// over the beam and none of the beam's under the plank: only the plank's long bottom edges, where
// they cross the beam's top, meet it. It rests there level and in place (before the edge spheres
// it fell through the beam).
TEST(RigidBodies, APlankAcrossABeamRestsOnItsEdges) {
  const std::string text = "name: t\ndimensions: 3\ndp: 0.02\ngravity: [0, 0, -9.81]\ntime: {end: 1}\n"
                           "tank: {origin: [0, 0, 0], size: [1, 1, 1]}\nfluid_blocks: [{min: [0, 0, 0], max: [0.3, 1, 0.3]}]\n"
                           "solids:\n  - name: plank\n    min: [0.35, 0.45, 0.201]\n    max: [0.75, 0.55, 0.251]\n"
                           "    motion: floating\n    density: 500\n"
                           "  - name: beam\n    min: [0.5, 0, 0]\n    max: [0.6, 1, 0.2]\n";
  const Case c = parse_case(text, "case.yaml");
  ASSERT_GT(c.bodies[0].contact.edges.size(), 0u);
  const double penetration = c.bodies[0].contact.penetration, top = 0.2;
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  Settled s;
  const double dt = 2e-4;
  for (int k = 0; k < 5000; ++k) {
    b.advance(k * dt, (k + 1) * dt);
    const double z = b.state(0).centre[2];
    s.lowest = std::min(s.lowest, z - 0.025 - top);
    if (k >= 4000) s.mean += z / 1000, s.low = std::min(s.low, z), s.high = std::max(s.high, z);
  }
  const BodyState& st = b.state(0);
  std::printf("plank across the beam: centre (%.6f, %.6f, %.6f) m, angles (%.3g, %.3g, %.3g) rad\n", st.centre[0], st.centre[1],
              st.centre[2], st.angles[0], st.angles[1], st.angles[2]);
  EXPECT_GT(s.lowest, -0.1 * c.dp);
  EXPECT_NEAR(s.mean, top + 0.025, 2 * penetration);
  EXPECT_LT(s.high - s.low, 0.3 * penetration);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(st.angles[a], 0.0, 1e-3);
  EXPECT_NEAR(st.centre[0], 0.55, 1e-3);
  EXPECT_NEAR(st.centre[1], 0.5, 1e-3);
}

// Contact between bodies: a narrow box (0.1 x 0.1 m, 5 kg) dropped onto a wide one (0.2 x 0.1 m,
// 10 kg) that rests on the floor comes to rest on it: its two lower corners on the wide box's top
// face, each carrying half its weight on the two bodies' combined stiffness (Simbody's rule,
// E = (s1 E1^(2/3))^(3/2)), and the wide box's corners on the floor carry both weights. Neither
// passes into the other; both stay level and in place.
TEST(RigidBodies, ABoxDroppedOnAnotherComesToRestOnIt) {
  const Case c = parse_case(case_2d("density: 500", "min: [0.5, 0.0]\n    max: [0.7, 0.1]") +
                                "  - name: top\n    min: [0.55, 0.2]\n    max: [0.65, 0.3]\n    motion: floating\n    density: 500\n",
                            "case.yaml");
  ASSERT_EQ(c.bodies.size(), 2u);
  const double R = 0.01 * c.dp, g = 9.81;
  const double W1 = c.bodies[0].mass * g, W2 = c.bodies[1].mass * g;
  RigidBodies b(c);
  b.set_loads({BodyLoad{}, BodyLoad{}});
  double deepest = 1.0;
  const double dt = 2e-4;
  Settled s1, s2;
  const int steps = 10000, tail = 1000;
  for (int k = 0; k < steps; ++k) {
    b.advance(k * dt, (k + 1) * dt);
    const double y1 = b.state(0).centre[1], y2 = b.state(1).centre[1];
    deepest = std::min(deepest, (y2 - 0.05) - (y1 + 0.05));  // the top box's bottom over the wide box's top
    if (k >= steps - tail) {
      s1.mean += y1 / tail, s2.mean += y2 / tail;
      s2.low = std::min(s2.low, y2), s2.high = std::max(s2.high, y2);
    }
  }
  // Each body's stiffness carries its own weight on one sphere at `penetration` (rigid_bodies.cpp).
  auto E = [&](double W, double p) { return 3.0 * W / (4.0 * std::sqrt(R) * std::pow(p, 1.5)); };
  const double p1 = c.bodies[0].contact.penetration, p2 = c.bodies[1].contact.penetration;
  const double e1 = std::pow(E(W2, p2), 2.0 / 3.0), e2 = std::pow(E(W1, p1), 2.0 / 3.0), s = e2 / (e1 + e2);
  const double Ec = std::pow(s * e1, 1.5);
  const double sunk_top = std::pow(3.0 * (W2 / 2) / (4.0 * Ec * std::sqrt(R)), 2.0 / 3.0);
  const double sunk_floor = p1 * std::pow((W1 + W2) / (2 * W1), 2.0 / 3.0);
  EXPECT_GT(deepest, -0.5 * c.dp);
  EXPECT_LT(deepest, R - sunk_top);  // it did land
  EXPECT_NEAR(s1.mean, 0.05 + R - sunk_floor, 0.1 * p1);
  EXPECT_NEAR(s2.mean - s1.mean, 0.1 + R - sunk_top, 0.1 * p2);
  EXPECT_LT(s2.high - s2.low, 0.3 * p2);
  // In place and level: the landing's rounding grows, through the contacts' friction, to some
  // 0.07 mm sideways (dp/100 allowed).
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(b.state(k).centre[0], 0.6, 0.01 * c.dp);
    EXPECT_NEAR(b.state(k).angles[2], 0.0, 1e-4);
  }
}

// Contact with a shaped tank: a disc (radius 5 cm) released at the middle of a circular canal
// (radius 0.2 m) falls to its bottom and rests there, its lowest contact sphere on the vessel's
// wall, sunk by `penetration` under its whole weight (the canal's curvature, 4 times the disc's,
// leaves one sphere in contact).
TEST(RigidBodies, ADiscInACircularTankRestsAtItsBottom) {
  const std::string text = "name: t\ndimensions: 2\ndp: 0.01\ngravity: [0, -9.81]\ntime: {end: 1}\n"
                           "tank: {disc: {centre: [0.2, 0.2], radius: 0.2}}\n"
                           "fluid_blocks: [{min: [0, 0], max: [0.4, 0.05]}]\n"
                           "solids:\n  - name: ball\n    disc: {centre: [0.2, 0.2], radius: 0.05}\n    motion: floating\n    density: 500\n";
  const Case c = parse_case(text, "case.yaml");
  ASSERT_TRUE(c.bodies[0].contact.on);
  const double penetration = c.bodies[0].contact.penetration, R = 0.01 * c.dp;
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  const Settled s = settle(b, 0, 10000, 1000, 2e-4, 0.05);
  EXPECT_GT(s.lowest, -0.5 * c.dp);
  EXPECT_LT(s.lowest, -penetration);
  // Its neighbouring spheres, 8e-5 m higher on the 96-gon, take a little of the weight.
  EXPECT_NEAR(s.mean, 0.05 + R - penetration, 0.15 * penetration);
  EXPECT_LT(s.high - s.low, 0.5 * penetration);  // a faint ringing on the contact's stiffness
  EXPECT_NEAR(b.state(0).centre[0], 0.2, 1e-6);
}

// A 2D tank with a box 0.2 x 0.1 m resting on its floor from x = `left`, `tank_motion` its motion
// keys, `extra` more solids.
std::string resting_box_case(const std::string& tank_motion, const std::string& extra = "", double left = 0.5) {
  return "name: t\ndimensions: 2\ndp: 0.01\ngravity: [0, -9.81]\ntime: {end: 1}\n"
         "tank: {origin: [0, 0], size: [1.2, 0.5]" + (tank_motion.empty() ? std::string() : ", motion: {" + tank_motion + "}") + "}\n"
         "fluid_blocks: [{min: [0.9, 0], max: [1.2, 0.1]}]\n"
         "solids:\n  - name: box\n    min: [" + std::to_string(left) + ", 0.0]\n    max: [" + std::to_string(left + 0.2) +
         ", 0.1]\n    motion: floating\n    density: 500\n" + extra;
}

// Contact with a moving tank: the tank sways, x = A sin(omega t) with A = 1 cm and a period of 1 s,
// ramped over one period; its floor's peak acceleration, A omega^2 = 0.39 m/s2, is far below
// Coulomb's mu g = 4.9 m/s2, so friction carries the box resting on the floor with the tank
// (creeping below the transition speed by some 0.03 mm); without friction it would stay put.
TEST(RigidBodies, ABoxOnTheFloorOfASwayingTankSwaysWithIt) {
  const Case c = parse_case(resting_box_case("translation: [0.01, 0], period: 1.0, ramp: 1.0"), "case.yaml");
  ASSERT_TRUE(c.bodies[0].contact.on);
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  const MotionSet motions(c.motions, c.dim);
  const double dt = 2e-4;
  double worst = 0.0, swing = 0.0;
  for (int k = 0; k < 15000; ++k) {  // 3 s
    b.advance(k * dt, (k + 1) * dt);
    const double tank = motions.sample(c.tank_motion, (k + 1) * dt).displacement[0];
    if (k * dt > 1.0) worst = std::max(worst, std::abs(b.state(0).centre[0] - 0.6 - tank)), swing = std::max(swing, std::abs(tank));
  }
  EXPECT_GT(swing, 0.0099);
  EXPECT_LT(worst, 0.01 * 0.01);  // 26 um
  EXPECT_NEAR(b.state(0).centre[1], 0.05, 0.5 * c.dp);
}

// Contact with a solid moved by a prescribed motion: a paddle (x from 0.2 to 0.3) swings 0.1 m to
// the right and back (period 2 s) and pushes the box resting on the floor in front of it (from
// x = 0.35) by 5 cm; the box never goes into the paddle (dp/10 at most) and friction stops it
// when the paddle turns back.
TEST(RigidBodies, AMovingSolidPushesABoxWithoutPassingIntoIt) {
  const Case c = parse_case(
      resting_box_case("", "  - name: paddle\n    min: [0.2, 0.0]\n    max: [0.3, 0.2]\n    motion: {translation: [0.1, 0], period: 2.0}\n", 0.35),
      "case.yaml");
  ASSERT_EQ(c.solids.size(), 2u);
  RigidBodies b(c);
  b.set_loads({BodyLoad{}});
  const MotionSet motions(c.motions, c.dim);
  const int paddle = c.solids[1].motion;
  const double dt = 2e-4;
  double closest = 1.0;
  for (int k = 0; k < 10000; ++k) {  // 2 s: out and back
    b.advance(k * dt, (k + 1) * dt);
    const double face = 0.3 + motions.sample(paddle, (k + 1) * dt).displacement[0];
    closest = std::min(closest, b.state(0).centre[0] - 0.1 - face);
  }
  EXPECT_GT(closest, -0.1 * c.dp);  // 0.49 mm: the paddle meets it at 0.3 m/s
  EXPECT_LT(closest, 0.0);  // it did touch
  EXPECT_GT(b.state(0).centre[0] - 0.45, 0.04);
  EXPECT_LT(b.state(0).centre[0] - 0.45, 0.06);
  EXPECT_LT(std::abs(b.state(0).velocity[0]), 1e-3);
  EXPECT_NEAR(b.state(0).angles[2], 0.0, 1e-3);
}

// Friction against the floor: a push below mu W leaves the resting box all but still (Simbody's
// continuous friction creeps below its transition velocity, 2 mm/s), one of 1.5 mu W slides it
// at (1.5 - 1) mu g; and a side wall stops it. The box (x from 0.9 to 1.1) settles from 1 cm above
// the floor.
TEST(RigidBodies, ABoxOnTheFloorSlidesAgainstCoulombFrictionUpToTheWall) {
  const Case c = parse_case(case_2d("density: 500\n    contact: {friction: 0.4}", "min: [0.9, 0.01]\n    max: [1.1, 0.11]"), "case.yaml");
  const double m = c.bodies[0].mass, W = m * 9.81, mu = 0.4;
  const double dt = 2e-4;
  auto settled = [&](RigidBodies& b) {
    b.set_loads({BodyLoad{}});
    for (int k = 0; k < 5000; ++k) b.advance(k * dt, (k + 1) * dt);
    ASSERT_LT(std::abs(b.state(0).velocity[1]), 0.01);  // but for a faint ringing
  };
  {
    RigidBodies b(c);
    settled(b);
    BodyLoad push;
    push.force = {0.8 * mu * W, 0.0, 0.0};
    b.set_loads({push});
    for (int k = 5000; k < 6000; ++k) b.advance(k * dt, (k + 1) * dt);
    EXPECT_LT(std::abs(b.state(0).velocity[0]), 2e-3);
  }
  RigidBodies b(c);
  settled(b);
  BodyLoad push;
  push.force = {1.5 * mu * W, 0.0, 0.0};
  b.set_loads({push});
  const double v0 = b.state(0).velocity[0];
  for (int k = 5000; k < 6000; ++k) b.advance(k * dt, (k + 1) * dt);  // 0.2 s
  EXPECT_NEAR((b.state(0).velocity[0] - v0) / 0.2, 0.5 * mu * 9.81, 0.05 * 0.5 * mu * 9.81);
  // On to the wall at x = 1.2: the box's right face (0.1 m right of its centre) stops there.
  double farthest = 0.0;
  for (int k = 6000; k < 10000; ++k) {
    b.advance(k * dt, (k + 1) * dt);
    farthest = std::max(farthest, b.state(0).centre[0] + 0.1);
  }
  EXPECT_GT(farthest, 1.2 - 1e-3);
  EXPECT_LT(farthest, 1.2 + 0.5 * c.dp);
  EXPECT_NEAR(b.state(0).centre[0] + 0.1, 1.2, 0.5 * c.dp);
}

// Steering (docs/live.md): a hinge's stiffness steered from 2 to 8 N m/rad doubles its natural
// frequency, so that the half period of the case's spring becomes a full one (the body back at
// rest); a spring or mooring line steered, numbered over the bodies; and what validate refuses.
TEST(RigidBodies, SteeredHingeAndSpringCoefficientsActFromTheNextStep) {
  const Case c = parse_case(case_2d("density: 500\n    hinge: {point: [0.6, 0.29], stiffness: 2.0}\n"
                                    "    springs: [{point: [0.6, 0.34], anchor: [0.6, 0.5], stiffness: 10}]"), "case.yaml");
  RigidBodies b(c);
  ASSERT_EQ(b.spring_count(), 1);
  EXPECT_DOUBLE_EQ(b.hinge(0).stiffness, 2.0);
  PhysicsParams P{};
  int every = 1;
  SteeringTarget target{&P, &every, nullptr, &b};
  const SteeringChange stiffer{0, 0.0, "hinge_stiffness", {0, 8.0}};
  ASSERT_FALSE(validate(stiffer, 2, nullptr, &c).has_value());
  apply(stiffer, target);
  EXPECT_DOUBLE_EQ(b.hinge(0).stiffness, 8.0);
  EXPECT_DOUBLE_EQ(b.hinge(0).damping, 0.0);
  // The spring through the centre of mass's vertical adds no torque at rest; the torque tau turns
  // the body about a new equilibrium tau / k: after pi / w (w = sqrt(k / I)) it is at 2 tau / k.
  const double I = c.bodies[0].inertia[2], k = 8.0, tau = 0.05, w = std::sqrt(k / I);
  BodyLoad l;
  l.torque = {0.0, 0.0, tau};
  b.set_loads({l});
  const int n = 400;
  run_steps(b, n, 3.14159265358979323846 / w / n);
  EXPECT_NEAR(b.state(0).angles[2], 2 * tau / k, 2e-3 * tau / k);
  const SteeringChange line{0, 0.0, "spring_damping", {0, 3.5}};
  ASSERT_FALSE(validate(line, 2, nullptr, &c).has_value());
  apply(line, target);
  EXPECT_DOUBLE_EQ(b.spring(0).stiffness, 10.0);
  EXPECT_DOUBLE_EQ(b.spring(0).damping, 3.5);
  auto why = [&](const SteeringChange& x, const Case* known) { return validate(x, 2, nullptr, known).value_or(""); };
  EXPECT_NE(why({0, 0.0, "spring_stiffness", {1, 5.0}}, &c).find("has 1 spring(s)"), std::string::npos);
  EXPECT_NE(why({0, 0.0, "hinge_damping", {0.5, 5.0}}, &c).find("whole number"), std::string::npos);
  EXPECT_NE(why({0, 0.0, "hinge_stiffness", {0, -1.0}}, &c).find("outside"), std::string::npos);
  const Case free = parse_case(case_2d(), "case.yaml");
  EXPECT_NE(why({0, 0.0, "hinge_stiffness", {0, 1.0}}, &free).find("has no hinge"), std::string::npos);
  EXPECT_EQ(why({0, 0.0, "spring_stiffness", {7, 5.0}}, nullptr), "");  // a log read before the run: ranges only
}

// A spring between two bodies (`to`): two boxes of 10 kg/m side by side, without gravity, the
// spring between their facing sides stretched by 2 cm: they swing against each other at
// w = sqrt(k / mu), mu = m1 m2 / (m1 + m2), their common centre of mass still; half a period
// later the stretch has turned to a squeeze of 2 cm.
TEST(RigidBodies, ASpringBetweenTwoBodiesPullsBothAndKeepsTheirCentre) {
  const std::string text =
      "name: t\ndimensions: 2\ndp: 0.01\ngravity: [0, 0]\ntime: {end: 1}\ntank: {origin: [0, 0], size: [1.2, 0.5]}\n"
      "fluid_blocks: [{min: [0, 0], max: [0.2, 0.3]}]\n"
      "solids:\n  - name: a\n    min: [0.3, 0.2]\n    max: [0.5, 0.3]\n    motion: floating\n    density: 500\n    free: [x]\n"
      "  - name: b\n    min: [0.6, 0.2]\n    max: [0.8, 0.3]\n    motion: floating\n    density: 500\n    free: [x]\n"
      "    springs: [{point: [0.6, 0.25], to: a, anchor: [0.5, 0.25], stiffness: 500, length: 0.08}]\n";
  const Case c = parse_case(text, "case.yaml");
  ASSERT_EQ(c.bodies[1].springs[0].to, 0);
  RigidBodies b(c);
  b.set_loads({BodyLoad{}, BodyLoad{}});
  const double m = 10.0, mu = m * m / (m + m), w = std::sqrt(500.0 / mu);
  const int n = 400;
  run_steps(b, n, 3.14159265358979323846 / w / n);
  const double gap = (b.state(1).centre[0] - 0.1) - (b.state(0).centre[0] + 0.1);
  EXPECT_NEAR(gap, 0.08 - 0.02, 1e-6);
  EXPECT_NEAR(0.5 * (b.state(0).centre[0] + b.state(1).centre[0]), 0.55, 1e-9);
  using test::error_of;
  std::string later = text;
  later.replace(later.find("to: a"), 5, "to: c");
  EXPECT_NE(error_of(later).find("'c' is not a floating solid listed before 'b'"), std::string::npos);
  std::string off = text;
  off.replace(off.find("anchor: [0.5, 0.25]"), 19, "anchor: [0.1, 0.25]");
  EXPECT_NE(error_of(off).find("the anchor lies outside solid 'a'"), std::string::npos);
}

TEST(RigidBodies, TheLoaderRefusesWhatCannotFloat) {
  using test::error_of;
  EXPECT_NE(error_of(case_2d("centre_of_mass: [0.6, 0.29]")).find("needs its density"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    mass: 3")).find("one of them"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: -5")).find("must be > 0"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    free: [z]")).find("'z' is not one of: x, y, rz"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    free: []")).find("key 'solids[0].free'"), std::string::npos);
  EXPECT_NE(error_of(test_sinking()).find("'sinking' is not a motion"), std::string::npos);
  EXPECT_NE(error_of(case_3d("density: 500\n    inertia: [1, 1, 5]")).find("is not the inertia of a body"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    hinge: {point: [0.2, 0.1]}")).find("the hinge lies outside solid 'box'"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    hinge: {point: [0.6, 0.24]}\n    free: [y]")).find("not both"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    springs: [{point: [0.6, 0.34], anchor: [0.6, 3.0], stiffness: 10}]"))
                .find("a mooring to nowhere"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    springs: [{point: [0.1, 0.1], anchor: [0.6, 0.5], stiffness: 10}]"))
                .find("the spring's end lies outside solid 'box'"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    springs: [{point: [0.6, 0.34], anchor: [0.6, 0.5], stiffness: 0}]")).find("must be > 0"),
            std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    contact: {penetration: 0.02}")).find("at most dp/2"), std::string::npos);
  EXPECT_NE(error_of(case_2d("density: 500\n    contact: {friction: -1}")).find("must be >= 0"), std::string::npos);
  EXPECT_FALSE(parse_case(case_2d("density: 500\n    contact: false"), "c.yaml").bodies[0].contact.on);
  EXPECT_FALSE(parse_case(case_2d("density: 500\n    hinge: {point: [0.6, 0.24]}"), "c.yaml").bodies[0].contact.on);
  std::string fixed = case_2d();
  fixed.replace(fixed.find("motion: floating"), 16, "hollow: true");
  EXPECT_NE(error_of(fixed).find("only a floating solid (motion: floating) takes 'density'"), std::string::npos);
  const std::string probe_on_static =
      "name: t\ndimensions: 2\ndp: 0.01\ntime: {end: 1}\ntank: {origin: [0, 0], size: [1, 0.5]}\nfluid_blocks: [{min: [0, 0], max: [0.3, 0.3]}]\n"
      "solids: [{name: wall, min: [0.5, 0], max: [0.6, 0.1]}]\nprobes: [{name: b, type: body, solid: wall}]\n";
  EXPECT_NE(error_of(probe_on_static).find("does not float"), std::string::npos);
  EXPECT_EQ(parse_case(case_2d() + "probes: [{name: p, type: pressure, position: [0.6, 0.2], follow: box}]\n", "c.yaml").probes[0].follow, 0);
}

}  // namespace
}  // namespace spate
