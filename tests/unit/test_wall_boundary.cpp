// Free-slip tank walls (physics/wall_boundary.hpp, apply_free_slip): a side wall particle of a tank
// with free-slip x walls mirrors only the normal velocity; floor, corners and solids stay no-slip.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace spate
