// Free-slip tank walls (physics/wall_boundary.hpp, apply_free_slip): a side wall particle of a tank
// with free-slip x walls mirrors only the normal velocity; floor, corners and solids stay no-slip.
// The log-law wall function (apply_log_law): the law of the wall solved for u*, and the wall
// particle's velocity that makes the laminar term's shear rho u*^2.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/wall_boundary.hpp"

namespace spate {
namespace {

TEST(WallBoundary, FreeSlipWallsMirrorOnlyTheNormalVelocity) {
  PhysicsParams P;
  P.dim = 2;
  P.materials.fluids = 1;
  P.materials.count = 3;  // fluid, tank, one solid
  P.free_slip_axes = 1u;  // x
  P.tank_lo[0] = 0.0f, P.tank_hi[0] = 1.0f;
  P.tank_lo[1] = 0.0f, P.tank_hi[1] = 2.0f;
  WallSums<2> s;
  s.w = 2.0f;
  s.v_w = Vec<2>{{0.6f, 0.8f}};  // kernel-weighted fluid velocity (0.3, 0.4)
  auto state = [&](float x, float y, std::uint8_t material) {
    WallState<2> st = finish_wall(P, s, material, Vec<2>{{x, y}});
    apply_free_slip<2>(P, Vec<2>{{x, y}}, material, s, st);
    return st.v;
  };
  const Vec<2> side = state(-0.01f, 1.0f, P.materials.tank());
  EXPECT_FLOAT_EQ(side[0], -0.3f);  // no penetration
  EXPECT_FLOAT_EQ(side[1], 0.4f);   // no shear
  const Vec<2> right = state(1.01f, 1.0f, P.materials.tank());
  EXPECT_FLOAT_EQ(right[1], 0.4f);
  for (const Vec<2>& no_slip : {state(0.5f, -0.01f, P.materials.tank()), state(-0.01f, -0.01f, P.materials.tank()),
                                state(-0.01f, 1.0f, P.materials.solid(0))}) {
    EXPECT_FLOAT_EQ(no_slip[0], -0.3f);
    EXPECT_FLOAT_EQ(no_slip[1], -0.4f);
  }
}

// u+ = ln(y+) / 0.41 + 5.2 above y+ = 11.2, u+ = y+ below: the returned u*^2 satisfies the law it
// is in, across the range of y+ a dam break's particles see (1 to 1e6).
TEST(WallBoundary, LogLawFrictionVelocitySolvesTheLawOfTheWall) {
  const float nu = 1e-6f;
  EXPECT_FLOAT_EQ(log_law_u_star2(0.01f, 1e-4f, nu), nu * 0.01f / 1e-4f) << "viscous sublayer: tau = mu u / y";
  EXPECT_EQ(log_law_u_star2(0.0f, 1e-3f, nu), 0.0f);
  for (float u : {0.05f, 0.3f, 2.4f, 10.0f})
    for (float y : {1e-4f, 1e-3f, 2.5e-3f, 1e-2f, 0.1f}) {
      const float us = std::sqrt(log_law_u_star2(u, y, nu));
      const float y_plus = y * us / nu;
      if (y_plus < 11.2f) {
        EXPECT_NEAR(u / us, y_plus, 1e-4f * y_plus) << "u " << u << " y " << y;
      } else {
        EXPECT_NEAR(u / us, std::log(y_plus) / 0.41f + 5.2f, 1e-4f * u / us) << "u " << u << " y " << y;
      }
    }
  // A 2.4 m/s surge over a smooth floor, 2.5 mm up: u* = 0.125 m/s (y+ = 312, u+ = ln(312) / 0.41 + 5.2 = 19.2),
  // a shear of 15.6 Pa.
  EXPECT_NEAR(1000.0f * log_law_u_star2(2.4f, 2.5e-3f, nu), 15.6f, 0.1f);
  // The two laws meet at the switch: no jump in the shear.
  const float y_switch = 11.2f * 11.2f * nu / 1.0f;
  EXPECT_NEAR(log_law_u_star2(1.0f, 0.999f * y_switch, nu), log_law_u_star2(1.0f, 1.001f * y_switch, nu),
              0.02f * log_law_u_star2(1.0f, y_switch, nu));
}

TEST(WallBoundary, LogLawWallParticleMakesTheLaminarShearTheLawOfTheWall) {
  PhysicsParams P;
  P.dim = 2;
  P.materials.fluids = 1;
  P.materials.count = 3;  // fluid, tank, one solid
  P.materials.fluid[0].rho0 = 1000.0f;
  P.materials.fluid[0].viscosity = 1e-3f;
  P.wall_shear = WallShear::LogLaw;
  P.tank_lo[0] = 0.0f, P.tank_hi[0] = 1.0f;
  P.tank_lo[1] = 0.0f, P.tank_hi[1] = 2.0f;
  const float nu = 1e-6f, depth = 0.0025f, d = 0.0075f;  // a first-layer floor particle; the fluid 5 mm above the face
  auto floor_velocity = [&](float u, float x = 0.5f, std::uint8_t material = 2) {
    WallSums<2> s;
    s.w = 2.0f;
    s.v_w = Vec<2>{{2.0f * u, 0.2f}};               // kernel-weighted fluid velocity (u, 0.1)
    s.rho_r_w = Vec<2>{{0.0f, -1000.0f * 2.0f * d}};  // the fluid d above the wall particle
    const Vec<2> x_wall{{x, -depth}};
    WallState<2> st = finish_wall(P, s, material, x_wall);
    apply_wall_shear<2>(P, x_wall, material, s, st);
    return st.v;
  };
  ASSERT_EQ(P.materials.tank(), 1);
  // 2.4 m/s at y = 5 mm: y+ ~ 600, the log law. The laminar term's shear mu (u - v_w) / d is rho u*^2.
  const Vec<2> fast = floor_velocity(2.4f, 0.5f, P.materials.tank());
  const float u_star2 = log_law_u_star2(2.4f, d - depth, nu);
  EXPECT_NEAR(nu * (2.4f - fast[0]) / d, u_star2, 1e-3f * u_star2);
  EXPECT_GT(nu * (2.4f - fast[0]) / d, 10.0f * nu * 2.0f * 2.4f / d) << "far more than the no-slip laminar shear";
  EXPECT_FLOAT_EQ(fast[1], -0.1f) << "no penetration, as Adami's mirror";
  // Creeping flow, y+ < 11: no slip, the linear profile extrapolated through the face.
  const Vec<2> slow = floor_velocity(1e-4f, 0.5f, P.materials.tank());
  EXPECT_NEAR(slow[0], -1e-4f * depth / (d - depth), 1e-9f);
  // A corner and a solid keep Adami's no slip.
  for (const Vec<2>& no_slip : {floor_velocity(2.4f, -0.001f, P.materials.tank()), floor_velocity(2.4f, 0.5f, P.materials.solid(0))})
    EXPECT_FLOAT_EQ(no_slip[0], -2.4f);
}

}  // namespace
}  // namespace spate
