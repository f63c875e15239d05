// Free-slip tank walls (physics/wall_boundary.hpp, apply_free_slip): a side wall particle of a tank
// with free-slip x walls mirrors only the normal velocity; floor, corners and solids stay no-slip.
// The log-law wall function (apply_log_law): the law of the wall solved for u*, the wall particle's
// velocity that makes the laminar term's shear rho u*^2, and the traction that the whole floor then
// exerts through the pair terms on water flowing with the log law's profile, at any dp. The
// artificial viscosity against a free-slip floor (PairKinematics::vr_av): no friction.
#include <gtest/gtest.h>

#include <cmath>

#include "lattice_params.hpp"
#include "physics/wall_boundary.hpp"

namespace spate {
namespace {

// 2D water (rho0 1000, mu 1e-3) for the wall treatments' formulas.
PhysicsParams water_2d() {
  PhysicsParams P;
  P.dim = 2;
  P.materials.fluid[0].rho0 = 1000.0f;
  P.materials.fluid[0].viscosity = 1e-3f;
  return P;
}

// Adami's wall pressure is clipped at 0 (a wall must not hold a free surface) unless the case's walls
// hold tension (fluid.wall_tension: flows without a free surface, where the clip lets fluid in
// tension tear off the wall); the density follows the pressure either way.
TEST(WallBoundary, WallsHoldTensionOnlyWhenTheCaseSaysSo) {
  PhysicsParams P = water_2d();
  P.materials.fluid[0].tait_b = 1000.0f * 25.0f / 7.0f;  // c0 = 5 m/s
  P.materials.fluid[0].gamma = 7.0f;
  P.materials.fluid[0].inv_gamma = 1.0f / 7.0f;
  P.materials.fluids = 1;
  P.materials.count = 2;  // fluid, tank
  WallSums<2> s;
  s.w = 2.0f;
  s.pw = -100.0f;  // the fluid around it at -50 Pa
  const Vec<2> x{{0.5f, -0.01f}};
  const WallState<2> clipped = finish_wall(P, s, P.materials.tank(), x);
  EXPECT_FLOAT_EQ(clipped.p, 0.0f);
  EXPECT_FLOAT_EQ(clipped.rho, 1000.0f);
  P.wall_tension = true;
  const WallState<2> held = finish_wall(P, s, P.materials.tank(), x);
  EXPECT_FLOAT_EQ(held.p, -50.0f);
  EXPECT_NEAR(held.rho, 1000.0f * std::pow(1.0f - 50.0f / P.materials.fluid[0].tait_b, 1.0f / 7.0f), 1e-3f);
  EXPECT_LT(held.rho, 1000.0f);
}

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
    apply_wall_shear<2>(P, box_tank_frame<2>(P, Vec<2>{{x, y}}, material), s, st);
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

// A shaped wall's particle carries its own frame (params.hpp WallFrame): the face's normal need
// not be an axis. Free slip and the log law on a face tilted by any angle give the velocity of the
// axis-aligned face, turned with it (the treatments are covariant), and the artificial viscosity
// sees the free-slip face slide along itself.
TEST(WallBoundary, ATiltedFacesFrameTurnsFreeSlipAndTheLogLawWithIt) {
  const PhysicsParams P = water_2d();
  const float depth = 0.0025f, d = 0.0075f;  // a first-layer wall particle; the fluid 5 mm off the face
  auto turn = [](const Vec<2>& v, float a) {
    return Vec<2>{{std::cos(a) * v[0] - std::sin(a) * v[1], std::sin(a) * v[0] + std::cos(a) * v[1]}};
  };
  for (FaceShear shear : {FaceShear::FreeSlip, FaceShear::LogLaw})
    for (float angle : {0.0f, 0.3f, 0.785398f, 2.0f, -1.2f}) {
      // A floor at angle 0: the fluid d above the wall particle, moving at (2.4, 0.1) over it.
      WallSums<2> s;
      s.w = 2.0f;
      s.v_w = turn(Vec<2>{{4.8f, 0.2f}}, angle);
      s.rho_r_w = turn(Vec<2>{{0.0f, -1000.0f * 2.0f * d}}, angle);
      WallFrame<2> face;
      face.n = turn(Vec<2>{{0.0f, 1.0f}}, angle);
      face.depth = depth;
      face.shear = shear;
      WallState<2> st = finish_wall(P, s, P.materials.tank(), Vec<2>{{0.5f, 0.5f}});
      apply_wall_shear<2>(P, face, s, st);
      const Vec<2> v = turn(st.v, -angle);  // back in the face's own axes
      EXPECT_NEAR(v[1], -0.1f, 1e-5f) << "no penetration at " << angle;
      if (shear == FaceShear::FreeSlip) {
        EXPECT_NEAR(v[0], 2.4f, 1e-5f) << "no shear at " << angle;
        ParticleState<2> j{{0.5f, 0.5f}, st.v, 1000.0f, 0.0f, P.materials.tank(), {0, 0}, {0, 0}};
        const Vec<2> slide = turn(sliding_velocity<2>(face, j), -angle);
        EXPECT_NEAR(slide[0], 2.4f, 1e-5f) << "the artificial viscosity sees the face slide";
        EXPECT_NEAR(slide[1], 0.0f, 1e-5f) << "but not move into the fluid";
      } else {
        const float u_star2 = log_law_u_star2(2.4f, d - depth, 1e-6f);
        EXPECT_NEAR(1e-6f * (2.4f - v[0]) / d, u_star2, 2e-3f * u_star2) << "the log law's shear at " << angle;
      }
    }
}

// On a moving wall (a solid's motion, a floating solid, a moving shaped tank: face.w its velocity
// there) the law of the wall holds in the wall's frame: the same relative flow gives the same shear
// whatever the wall's own speed along itself (Galilean invariance), water moving with the wall
// feels none, and the normal component stays Adami's mirror.
TEST(WallBoundary, TheLogLawOnAMovingWallActsOnTheFlowRelativeToIt) {
  const PhysicsParams P = water_2d();
  const float depth = 0.0025f, d = 0.0075f;  // a first-layer wall particle; the fluid 5 mm off the face
  auto wall_velocity = [&](const Vec<2>& fluid, const Vec<2>& w, const Vec<2>& n) {
    WallSums<2> s;
    s.w = 2.0f;
    s.v_w = Vec<2>{{2.0f * fluid[0], 2.0f * fluid[1]}};
    s.rho_r_w = Vec<2>{{-1000.0f * 2.0f * d * n[0], -1000.0f * 2.0f * d * n[1]}};
    WallFrame<2> face;
    face.n = n;
    face.depth = depth;
    face.shear = FaceShear::LogLaw;
    face.w = w;
    WallState<2> st{0.0f, 1000.0f, Vec<2>{{2.0f * w[0] - fluid[0], 2.0f * w[1] - fluid[1]}}};  // Adami's mirror
    apply_wall_shear<2>(P, face, s, st);
    return st.v;
  };
  const float c = std::cos(0.4f), sn = std::sin(0.4f);
  const Vec<2> n{{-sn, c}}, t{{c, sn}};  // a floor tilted by 0.4 rad
  auto along = [&](const Vec<2>& v) { return v[0] * t[0] + v[1] * t[1]; };
  auto across = [&](const Vec<2>& v) { return v[0] * n[0] + v[1] * n[1]; };
  auto mix = [&](float a, float b) { return Vec<2>{{a * t[0] + b * n[0], a * t[1] + b * n[1]}}; };
  // The fluid 2.4 m/s along the face and 0.1 off it, over a wall at rest and over one sliding at
  // 1.5 m/s with the fluid at 3.9 (the same 2.4 relative).
  const Vec<2> still = wall_velocity(mix(2.4f, 0.1f), mix(0.0f, 0.0f), n);
  const Vec<2> sliding = wall_velocity(mix(3.9f, 0.1f), mix(1.5f, 0.0f), n);
  EXPECT_NEAR(along(sliding) - 1.5f, along(still), 1e-4f) << "the shear depends on the relative flow only";
  const float u_star2 = log_law_u_star2(2.4f, d - depth, 1e-6f);
  EXPECT_NEAR(1e-6f * (3.9f - along(sliding)) / d, u_star2, 2e-3f * u_star2);
  EXPECT_NEAR(across(sliding), -0.1f, 1e-5f) << "Adami's mirrored normal component";
  // Water carried along with the wall: no shear (the wall particle takes the fluid's velocity).
  const Vec<2> carried = wall_velocity(mix(1.5f, 0.0f), mix(1.5f, 0.0f), n);
  EXPECT_NEAR(along(carried), 1.5f, 1e-6f);
  // A wall moving into the fluid (w along n): the tangential law is untouched by it.
  const Vec<2> pushing = wall_velocity(mix(2.4f, 0.3f), mix(0.0f, 0.2f), n);
  EXPECT_NEAR(along(pushing), along(still), 1e-4f);
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
    apply_wall_shear<2>(P, box_tank_frame<2>(P, x_wall, material), s, st);
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

// The force {along, off} the floor, per unit floor length over rho, that the three floor layers of
// the lattice tank exert through the real pair terms (the wall pass, then the fluid pair loop as a
// run with free-slip or moving walls takes it, j.w = boundary_velocity) on one column of water at
// spacing dp whose velocity depends on the height alone: the flow does not change along x, so
// neither do the wall states.
template <class Velocity>
Vec<2> floor_force(const PhysicsParams& P, float dp, Velocity velocity_at) {
  const FluidMaterial& M = P.materials.fluid[0];
  const float x0 = 0.2f + 0.5f * dp;  // mid-floor of the 0.4 m tank
  const int reach = static_cast<int>(std::ceil(2.0f * P.h / dp)) + 1;
  auto fluid_at = [&](int col, int row) {
    const float y = (row + 0.5f) * dp;
    return ParticleState<2>{{x0 + col * dp, y}, velocity_at(y), M.rho0, 0.0f, 0, {0, 0}, {0, 0}};
  };
  ParticleState<2> wall[3];
  for (int layer = 0; layer < 3; ++layer) {
    const Vec<2> x_wall{{x0, -(layer + 0.5f) * dp}};
    WallSums<2> s;
    for (int col = -reach; col <= reach; ++col)
      for (int row = 0; row <= reach; ++row) accumulate_wall_pair<WendlandC2, 2>(P, x_wall, fluid_at(col, row), s);
    WallState<2> st = finish_wall(P, s, P.materials.tank(), x_wall);
    apply_wall_shear<2>(P, box_tank_frame<2>(P, x_wall, P.materials.tank()), s, st);
    wall[layer] = ParticleState<2>{x_wall, st.v, st.rho, 0.0f, P.materials.tank(), {0, 0}, {0, 0}};
  }
  Vec<2> force{{0.0f, 0.0f}};
  for (int row = 0; row <= reach; ++row) {
    const ParticleState<2> i = fluid_at(0, row);
    for (int col = -reach; col <= reach; ++col)
      for (const ParticleState<2>& w : wall) {
        ParticleState<2> j = w;
        j.x[0] = x0 + col * dp;
        j.w = boundary_velocity<2>(P, j);  // 0: the tank is at rest
        j.w_av = sliding_velocity<2>(box_tank_frame<2>(P, j.x, j.material), j);
        const Vec<2> a = fluid_pair_terms<WendlandC2, 2, true, true>(P, M, i, j).acc;
        for (int k = 0; k < 2; ++k) force[k] += M.mass * a[k];
      }
  }
  for (int k = 0; k < 2; ++k) force[k] /= dp * M.rho0;
  return force;
}

// What the floor exerts on water that flows with the law of the wall's own profile, u(y) = u*
// (ln(y u*/nu)/0.41 + 5.2) with u* = 0.1 m/s (1.9 m/s at 2.5 mm, 2.5 m/s at 3 cm: a dam-break
// surge): the friction per unit floor length is rho u*^2 to a few percent, and the same at every
// resolution, because the wall particles and the fluid they see scale with dp together. Measured
// 0.969 rho u*^2 at H/60, H/120 and H/240 (the laminar term's sum across the face is not exactly
// the shear across the mean distance d); the artificial viscosity and pressures are off here, so
// the laminar term is all that acts. Laminar no slip (Adami's mirror, nu = 1e-6 m^2/s) exerts
// 0.069 rho u*^2 on the same profile.
float floor_traction(float dp, bool log_law) {
  PhysicsParams P = lattice_params(2, "fluid:\n  viscosity: 0.001\n  artificial_viscosity: 0\n", dp);
  P.wall_shear = log_law ? WallShear::LogLaw : WallShear::Laminar;
  const float nu = 1e-6f, u_star = 0.1f;
  auto u_log = [&](float y) { return Vec<2>{{u_star * (std::log(y * u_star / nu) / 0.41f + 5.2f), 0.0f}}; };
  return -floor_force(P, dp, u_log)[0] / (u_star * u_star);  // in rho u*^2, positive against the flow
}

TEST(WallBoundary, TheLogLawFloorExertsRhoUStarSquaredAtEveryResolution) {
  const float h60 = floor_traction(0.005f, true), h120 = floor_traction(0.0025f, true), h240 = floor_traction(0.00125f, true);
  for (float t : {h60, h120, h240}) {
    EXPECT_GT(t, 0.90f);
    EXPECT_LT(t, 1.00f);
  }
  EXPECT_NEAR(h120, h60, 0.01f * h60) << "the wall function does not depend on dp";
  EXPECT_NEAR(h240, h60, 0.01f * h60);
  EXPECT_LT(floor_traction(0.005f, false), 0.2f * h60) << "laminar no slip rubs far less on a turbulent profile";
}

// What the floor exerts on water streaming over it at u and sinking towards it at 0.1 m/s, with the
// artificial viscosity on (alpha = 0.02, wall factor 1) and no laminar viscosity. A free-slip floor
// slides with the water (PairKinematics::vr_av), so the artificial viscosity only resists the
// approach; against a no-slip floor at rest it also rubs (artificial_alpha: the pair direction to a
// wall particle ahead makes the slide an approach).
Vec<2> av_floor_force(bool free_slip, float u) {
  PhysicsParams P = lattice_params(2, "fluid:\n  viscosity: 0\n  artificial_viscosity: 0.02\n");
  P.free_slip_axes = free_slip ? 2u : 0u;  // the floor (normal y); the loader's tank.free_slip: [y]
  return floor_force(P, 0.01f, [&](float) { return Vec<2>{{u, -0.1f}}; });
}

TEST(WallBoundary, TheArtificialViscosityDoesNotRubOnAFreeSlipFloor) {
  PhysicsParams P = lattice_params(2);
  EXPECT_FALSE(P.walls_have_velocity());
  P.free_slip_axes = 2u;
  EXPECT_TRUE(P.walls_have_velocity()) << "free-slip runs take the pair loop that carries wall velocities";
  const Vec<2> no_slip = av_floor_force(false, 2.0f), free_slip = av_floor_force(true, 2.0f);
  EXPECT_LT(no_slip[0], -0.01f) << "against a floor at rest the artificial viscosity is a friction";
  EXPECT_NEAR(free_slip[0], 0.0f, 1e-4f * std::fabs(no_slip[0])) << "a free-slip floor exerts no friction";
  // It resists the approach as a floor at rest resists water sinking onto it without sliding.
  const Vec<2> sinking = av_floor_force(false, 0.0f);
  EXPECT_GT(sinking[1], 0.0f);
  EXPECT_NEAR(free_slip[1], sinking[1], 1e-4f * sinking[1]);
}

}  // namespace
}  // namespace spate
