// Particle shifting of delta-plus-SPH (solver/physics/shifting.hpp) on 2D lattices of spacing dp:
// nothing moves on a perfect lattice, a displaced particle is pushed back towards its lattice site,
// a particle on a free surface is never pushed out of the fluid, and a splashed one is left alone;
// the volume-consistent density changes by -rho div(dr), the summation density's change; the
// corrected velocity follows a shifted particle along a linear field.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lattice_params.hpp"
#include "physics/shifting.hpp"

namespace spate {
namespace {

struct Lattice2D {
  PhysicsParams P = lattice_params(2, "shifting:\n  enabled: true\n");
  const FluidMaterial& M = P.materials.fluid[0];
  float dt = 1e-4f;
  // Fluid sites (i dp, j dp) for |i| <= 6 and -12 <= j <= top.
  std::vector<ParticleState<2>> sites(int top) const {
    std::vector<ParticleState<2>> out;
    for (int i = -6; i <= 6; ++i)
      for (int j = -12; j <= top; ++j) out.push_back(ParticleState<2>{{i * P.dp, j * P.dp}, {0, 0}, M.rho0, 0.0f, 0, {0, 0}, {0, 0}});
    return out;
  }
  Vec<2> shift_of(const Vec<2>& xi, const std::vector<ParticleState<2>>& all, std::uint8_t material_i = 0) const {
    ShiftingSums<2> s;
    const float w_dp = WendlandC2::value(P.dp * P.inv_h, P.kernel_norm);
    for (const auto& j : all) accumulate_shifting_pair<WendlandC2, 2>(P, M, material_i, w_dp, xi, j, s);
    return shifting_displacement<2>(P, M, s, dt);
  }
};

TEST(Shifting, NothingMovesOnAPerfectLattice) {
  Lattice2D L;
  const Vec<2> dr = L.shift_of(Vec<2>{0, 0}, L.sites(6));
  EXPECT_LT(std::hypot(dr[0], dr[1]), 1e-6f * L.P.dp);
}

TEST(Shifting, ADisplacedParticleIsPushedBackTowardsItsSite) {
  Lattice2D L;
  auto all = L.sites(6);
  for (auto& p : all)
    if (p.x[0] == 0.0f && p.x[1] == 0.0f) p.x[0] = 0.3f * L.P.dp;
  const Vec<2> dr = L.shift_of(Vec<2>{0.3f * L.P.dp, 0}, all);
  EXPECT_LT(dr[0], 0.0f);                       // back towards x = 0
  EXPECT_GT(-dr[0], 1e-4f * L.P.dp);
  EXPECT_LT(-dr[0], 0.3f * L.P.dp);             // never past the site in one step
  EXPECT_NEAR(dr[1], 0.0f, 1e-6f * L.P.dp);     // the lattice is symmetric in y
}

TEST(Shifting, AFreeSurfaceParticleIsNotPushedOutOfTheFluid) {
  Lattice2D L;
  auto all = L.sites(0);  // the free surface is the row y = 0
  const Vec<2> top = L.shift_of(Vec<2>{0, 0}, all);
  EXPECT_LE(top[1], 1e-9f);
  // One row below the surface the kernel is still cut: same rule.
  const Vec<2> below = L.shift_of(Vec<2>{0, -L.P.dp}, all);
  EXPECT_LE(below[1], 1e-9f);
  // Deep inside, nothing to correct.
  const Vec<2> deep = L.shift_of(Vec<2>{0, -5 * L.P.dp}, all);
  EXPECT_LT(std::hypot(deep[0], deep[1]), 1e-6f * L.P.dp);
}

// A closed flow (shifting.free_surface: false): the same cut kernel is a void, and the particles on
// its edge are shifted into it (up, out of the lattice), one as isolated as a splash too.
TEST(Shifting, InAClosedFlowAVoidIsFilled) {
  Lattice2D L;
  L.P.shifting.free_surface = false;
  const auto all = L.sites(0);
  EXPECT_GT(L.shift_of(Vec<2>{0, 0}, all)[1], 1e-4f * L.P.dp);
  EXPECT_GT(L.shift_of(Vec<2>{0, -L.P.dp}, all)[1], 1e-6f * L.P.dp);
  std::vector<ParticleState<2>> pair{{{0, 0}, {0, 0}, L.M.rho0, 0.0f, 0, {0, 0}, {0, 0}}, {{0.9f * L.P.dp, 0}, {0, 0}, L.M.rho0, 0.0f, 0, {0, 0}, {0, 0}}};
  EXPECT_LT(L.shift_of(Vec<2>{0, 0}, pair)[0], 0.0f) << "away from its close neighbour";
}

// Several fluids: fluid 1 above y = 0.5 dp, fluid 0 below. A particle of fluid 0 on the interface
// row, displaced diagonally, is shifted along the interface (its normal leaning with the offset),
// while the same particle with every neighbour of its own fluid is pushed back diagonally.
TEST(Shifting, AtAnInterfaceParticlesSlideAlongIt) {
  Lattice2D L;
  L.P.materials.fluids = 2;
  L.P.materials.fluid[1] = L.M;
  auto all = L.sites(6);
  const Vec<2> xi{0.3f * L.P.dp, -0.2f * L.P.dp};
  for (auto& p : all)
    if (p.x[0] == 0.0f && p.x[1] == 0.0f) p.x = xi;
  const Vec<2> one_fluid = L.shift_of(xi, all);
  EXPECT_LT(one_fluid[0], 0.0f);
  EXPECT_GT(std::fabs(one_fluid[1]), 1e-3f * std::fabs(one_fluid[0])) << "the lone fluid's shift has a vertical part";
  for (auto& p : all) p.material = p.x[1] > 0.5f * L.P.dp ? 1 : 0;
  const Vec<2> two_fluids = L.shift_of(xi, all, 0);
  EXPECT_LT(two_fluids[0], 0.0f) << "back towards its site along the interface";
  // The interface normal leans a little with the particle's offset: its vertical part is what
  // remains, a tenth of the lone fluid's at most.
  EXPECT_LT(std::fabs(two_fluids[1]), 0.1f * std::fabs(one_fluid[1])) << "next to nothing across the (horizontal) interface";
}

TEST(Shifting, ASplashedParticleIsLeftAlone) {
  Lattice2D L;
  std::vector<ParticleState<2>> pair{{{0, 0}, {0, 0}, L.M.rho0, 0.0f, 0, {0, 0}, {0, 0}}, {{0.9f * L.P.dp, 0}, {0, 0}, L.M.rho0, 0.0f, 0, {0, 0}, {0, 0}}};
  const Vec<2> dr = L.shift_of(Vec<2>{0, 0}, pair);
  EXPECT_EQ(dr[0], 0.0f);
  EXPECT_EQ(dr[1], 0.0f);
}

// The volume-consistent density (shifting.volume_consistent): the density change of the particle
// at the origin of a lattice (itself one of `all`) under the displacements dr_j of all, its own dri.
float density_change(const Lattice2D& L, const std::vector<ParticleState<2>>& all, const std::vector<Vec<2>>& dr, const Vec<2>& dri,
                     float rho_i) {
  const Vec<2> xi{0, 0};
  float sum = 0.0f;
  for (std::size_t j = 0; j < all.size(); ++j) sum += shift_volume_term<WendlandC2, 2>(L.P, L.M, xi, dri, all[j].x, dr[j]);
  return shift_density_change(rho_i, sum);
}

TEST(Shifting, ATranslationLeavesTheDensityAlone) {
  Lattice2D L;
  const auto all = L.sites(6);
  const Vec<2> d{0.07f * L.P.dp, -0.11f * L.P.dp};
  EXPECT_EQ(density_change(L, all, std::vector<Vec<2>>(all.size(), d), d, 1003.0f), 0.0f);
}

// A uniform dilation dr = eps x (div dr = 2 eps in 2D) lowers the density by rho 2 eps, to the
// lattice's accuracy, and by as much (within 5%) as it lowers the summation density sum_j m W_ij of
// the dilated lattice: the continuity density stays the density of the particles' arrangement. A
// contraction raises it by the same.
TEST(Shifting, ADilationLowersTheDensityByItsDivergence) {
  Lattice2D L;
  const auto all = L.sites(6);
  const float eps = 1e-3f, rho = 1000.0f;
  for (const float e : {eps, -eps}) {
    std::vector<Vec<2>> dr;
    for (const auto& p : all) dr.push_back(e * p.x);
    const float change = density_change(L, all, dr, Vec<2>{0, 0}, rho);
    EXPECT_NEAR(change, -rho * 2.0f * e, 0.01f * rho * 2.0f * eps) << "eps " << e;
    double before = 0.0, after = 0.0;
    for (const auto& p : all) {
      const double r = std::hypot(p.x[0], p.x[1]);
      before += L.M.mass * WendlandC2::value(static_cast<float>(r) * L.P.inv_h, L.P.kernel_norm);
      after += L.M.mass * WendlandC2::value(static_cast<float>(r * (1.0 + e)) * L.P.inv_h, L.P.kernel_norm);
    }
    // 3.7% apart: the gradient's lattice renormalisation (kernels.hpp) makes sum V F r^2 exactly
    // -Dim, which the summation of W on the lattice is not made to match.
    EXPECT_NEAR(change, (after - before) * rho / before, 0.05f * rho * 2.0f * eps) << "the summation density's change, eps " << e;
  }
}

// shifting.correct_velocity: on a lattice carrying a linear velocity field v = A x (a shear and a
// strain), the velocity's change at the shifted position is A dr, the field's own value there, to
// the lattice gradient's accuracy; a uniform velocity gives no change, also where the kernel is cut.
TEST(Shifting, TheVelocityFollowsAShiftedParticleAlongALinearField) {
  Lattice2D L;
  const float A[2][2] = {{3.0f, 5.0f}, {-2.0f, -3.0f}};  // v_a = A[a][b] x_b
  auto all = L.sites(6);
  for (auto& p : all)
    for (int a = 0; a < 2; ++a) p.v[a] = A[a][0] * p.x[0] + A[a][1] * p.x[1] + (a == 0 ? 0.4f : -0.1f);
  const ParticleState<2> centre = all[6 * 19 + 12];  // the site (0, 0)
  ASSERT_EQ(centre.x[0], 0.0f);
  ASSERT_EQ(centre.x[1], 0.0f);
  VelocityGradient<2> grad;
  for (const auto& j : all) accumulate_velocity_gradient<WendlandC2, 2>(L.P, centre, j, L.M.mass / L.M.rho0, grad);
  const Vec<2> dr{0.07f * L.P.dp, -0.11f * L.P.dp};
  const Vec<2> dv = shift_velocity_change<2>(grad, dr);
  for (int a = 0; a < 2; ++a) {
    const float exact = A[a][0] * dr[0] + A[a][1] * dr[1];
    EXPECT_NEAR(dv[a], exact, 1e-3f * std::fabs(exact)) << "component " << a;
  }
  // A uniform velocity under a cut kernel (the free surface row): nothing to carry.
  auto surface = L.sites(0);
  for (auto& p : surface) p.v = Vec<2>{0.4f, -0.1f};
  VelocityGradient<2> uniform;
  for (const auto& j : surface) accumulate_velocity_gradient<WendlandC2, 2>(L.P, surface[6 * 13 + 12], j, L.M.mass / L.M.rho0, uniform);
  const Vec<2> none = shift_velocity_change<2>(uniform, dr);
  EXPECT_EQ(none[0], 0.0f);
  EXPECT_EQ(none[1], 0.0f);
}

}  // namespace
}  // namespace spate
