// The flow drive (sim/flow_drive.hpp): on a model flow dU/dt = f - D with a steady drag D it
// reaches the target mean velocity at the rate its response time sets, settles on f = D, and its
// saved state restores bit for bit.
#include <gtest/gtest.h>

#include <cmath>

#include "../../solver/case/case.hpp"
#include "../../solver/physics/fluid_interactions.hpp"
#include "../../solver/sim/flow_drive.hpp"

namespace spate {
namespace {

Case driven_case(double response_time) {
  Case c;
  c.dim = 2;
  c.periodic = {true, false, false};
  c.drive.on = true;
  c.drive.axes = {true, false, false};
  c.drive.mean_velocity = {0.2, 0, 0};
  c.drive.response_time = response_time;
  return c;
}

// One explicit step of the model flow with the body force the drive set.
double model_step(double u, const PhysicsParams& P, double drag, double dt) { return u + dt * (P.body_force[0] - drag); }

TEST(FlowDrive, ReachesTheMeanVelocityAtItsResponseTimeAndHoldsTheDrag) {
  const double dt = 1e-3, tau = 0.05, drag = 0.3;
  FlowDrive drive(driven_case(tau));
  PhysicsParams P;
  double u = 0.0;
  drive.update(P, {u, 0, 0}, 0.0, dt);
  for (int n = 1; n <= 50; ++n) {  // one response time
    u = model_step(u, P, drag, dt);
    drive.update(P, {u, 0, 0}, dt, dt);
  }
  // The error decays as (1 - dt/tau) per step once the drag is known (from the second step on).
  const double expected = 0.2 * (1.0 - std::pow(1.0 - dt / tau, 50));
  EXPECT_NEAR(u, expected, 0.02 * 0.2);
  for (int n = 0; n < 2000; ++n) {
    u = model_step(u, P, drag, dt);
    drive.update(P, {u, 0, 0}, dt, dt);
  }
  EXPECT_NEAR(u, 0.2, 1e-6);
  EXPECT_NEAR(drive.force()[0], drag, 1e-3);  // float's body force: the steady force is the drag
  EXPECT_EQ(P.body_force[1], 0.0f);           // a walled axis is not driven
}

TEST(FlowDrive, ZeroResponseTimeCorrectsInOneStep) {
  const double dt = 1e-3, drag = 0.3;
  FlowDrive drive(driven_case(0.0));
  PhysicsParams P;
  double u = 0.1;
  drive.update(P, {u, 0, 0}, 0.0, dt);
  for (int n = 0; n < 3; ++n) {
    u = model_step(u, P, drag, dt);
    drive.update(P, {u, 0, 0}, dt, dt);
  }
  EXPECT_NEAR(u, 0.2, 1e-6);
}

TEST(FlowDrive, SavedStateRestoresBitForBitAndBadStateIsRefused) {
  const double dt = 1e-3;
  FlowDrive a(driven_case(0.02));
  PhysicsParams Pa, Pb;
  a.update(Pa, {0.05, 0, 0}, 0.0, dt);
  a.update(Pa, {0.0512345678901, 0, 0}, dt, dt);
  FlowDrive b(driven_case(0.02));
  b.restore(a.save());
  b.apply(Pb);
  EXPECT_EQ(Pa.body_force[0], Pb.body_force[0]);
  a.update(Pa, {0.06, 0, 0}, dt, dt);
  b.update(Pb, {0.06, 0, 0}, dt, dt);
  EXPECT_EQ(a.force()[0], b.force()[0]);
  EXPECT_EQ(a.save(), b.save());

  EXPECT_THROW(b.restore(""), std::runtime_error);             // a drive and no state
  EXPECT_THROW(b.restore("force 1 2 3 mean 4 5"), std::runtime_error);  // cut short
  EXPECT_THROW(b.restore("force 1 2 x mean 4 5 6"), std::runtime_error);
  Case plain;
  EXPECT_THROW(FlowDrive(plain).restore(a.save()), std::runtime_error);  // a state and no drive
  EXPECT_TRUE(FlowDrive(plain).save().empty());
}

// The relaxation zone's acceleration (u* - v) / time inside its box, with the parabolic profile
// across its height, and nothing outside it.
TEST(RelaxationZone, PullsTheVelocityTowardsTheProfileInsideItsBoxOnly) {
  PhysicsParams P;
  P.zone.lo[0] = 2.0f, P.zone.hi[0] = 2.2f, P.zone.lo[1] = 0.0f, P.zone.hi[1] = 0.4f;
  P.zone.velocity[0] = 0.3f;
  P.zone.inv_time = 20.0f;
  P.zone.parabolic = true;
  ParticleState<2> s;
  s.x = Vec<2>{2.1f, 0.1f};  // a quarter of the height: 3/4 of the peak
  s.v = Vec<2>{0.1f, 0.05f};
  Vec<2> acc = zero_vec<2>();
  relax_in_zone(P, s, acc);
  EXPECT_NEAR(acc[0], (0.75f * 0.3f - 0.1f) * 20.0f, 1e-5);
  EXPECT_NEAR(acc[1], -0.05f * 20.0f, 1e-6);
  s.x = Vec<2>{1.9f, 0.1f};
  acc = zero_vec<2>();
  relax_in_zone(P, s, acc);
  EXPECT_EQ(acc[0], 0.0f);
  EXPECT_EQ(acc[1], 0.0f);
}

}  // namespace
}  // namespace spate
