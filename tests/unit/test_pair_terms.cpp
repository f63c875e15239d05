// The plain fluid pair loop is compiled a second time without the Riemann options' terms
// (Riemann = false in dispatch_pair_flags, solver/physics/dispatch.hpp). Those terms add exactly
// zero when neither option is on, so leaving them out must give the same bits: checked pair by
// pair on random pairs (fluid and wall neighbours, approaching and receding, hydrostatic and
// disturbed pressures); with `momentum.flux: riemann` the terms do change the result, so the
// comparison can fail. And only the plain loop, with neither option, is chosen without them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "lattice_params.hpp"
#include "physics/dispatch.hpp"
#include "physics/fluid_interactions.hpp"
#include "physics/multiphase_interactions.hpp"

namespace spate {
namespace {

bool same_bits(const FluidRates<2>& a, const FluidRates<2>& b) {
  return std::memcmp(a.acc.c, b.acc.c, sizeof(a.acc.c)) == 0 && std::memcmp(&a.density_rate, &b.density_rate, sizeof(float)) == 0;
}

// Random pairs within the support: i a fluid particle, j a fluid or a wall particle.
template <class F>
void for_random_pairs(const PhysicsParams& P, F&& f) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const FluidMaterial& M = P.materials.fluid[0];
  for (int n = 0; n < 2000; ++n) {
    ParticleState<2> i{{0.2f, 0.2f}, {u(rng), u(rng)}, M.rho0 * (1.0f + 0.01f * u(rng)), 0.0f, 0, {0, 0}, {0, 0}};
    ParticleState<2> j = i;
    const float r = 2.0f * P.h * (0.5f + 0.5f * u(rng)), a = 3.14159f * u(rng);
    j.x = Vec<2>{{i.x[0] + r * std::cos(a), i.x[1] + r * std::sin(a)}};
    j.v = Vec<2>{{u(rng), u(rng)}};
    j.rho = M.rho0 * (1.0f + 0.01f * u(rng));
    j.material = n % 3 == 0 ? P.materials.tank() : 0;
    i.p = 1000.0f * (1.0f + u(rng));
    j.p = 1000.0f * (1.0f + u(rng));
    f(M, i, j);
  }
}

TEST(PairTerms, LeavingOutTheRiemannTermsChangesNoBitWhenTheOptionsAreOff) {
  const PhysicsParams P = lattice_params(2);
  ASSERT_FALSE(pair_loop_flags(P).riemann);
  int pairs = 0;
  for_random_pairs(P, [&](const FluidMaterial& M, const ParticleState<2>& i, const ParticleState<2>& j) {
    const auto with = fluid_pair_terms<WendlandC2, 2, true, false, true>(P, M, i, j);
    const auto without = fluid_pair_terms<WendlandC2, 2, true, false, false>(P, M, i, j);
    EXPECT_TRUE(same_bits(with, without)) << "pair " << pairs;
    const auto mp_with = multiphase_pair_terms<WendlandC2, 2, true, false, true>(P, M, i, j, neighbour_fluid(P, j.material), M.viscosity);
    const auto mp_without = multiphase_pair_terms<WendlandC2, 2, true, false, false>(P, M, i, j, neighbour_fluid(P, j.material), M.viscosity);
    EXPECT_TRUE(same_bits(mp_with, mp_without)) << "pair " << pairs;
    ++pairs;
  });
  EXPECT_EQ(pairs, 2000);
}

TEST(PairTerms, WithTheRiemannFluxTheTermsMatter) {
  PhysicsParams P = lattice_params(2);
  P.flux = MomentumFlux::Riemann;
  EXPECT_TRUE(pair_loop_flags(P).riemann);
  int differ = 0;
  for_random_pairs(P, [&](const FluidMaterial& M, const ParticleState<2>& i, const ParticleState<2>& j) {
    differ += !same_bits(fluid_pair_terms<WendlandC2, 2, true, false, true>(P, M, i, j),
                         fluid_pair_terms<WendlandC2, 2, true, false, false>(P, M, i, j));
  });
  EXPECT_GT(differ, 100) << "approaching fluid pairs feel the limiter's dissipation";
}

// Which loops exist: without the Riemann terms only for one fluid, static walls and no option.
TEST(PairTerms, OnlyThePlainLoopIsChosenWithoutTheRiemannTerms) {
  auto chosen = [](PairLoopFlags flags) {
    bool riemann = false;
    dispatch_pair_flags(flags, [&]<bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>() { riemann = Riemann; });
    return riemann;
  };
  EXPECT_FALSE(chosen({true, false, false, false}));
  EXPECT_FALSE(chosen({false, false, false, false}));
  EXPECT_TRUE(chosen({true, false, false, true}));
  EXPECT_TRUE(chosen({true, true, false, false}));
  EXPECT_TRUE(chosen({true, false, true, false}));
}

// fluid.wall_artificial_viscosity: the artificial viscosity against a wall at rest is a friction on a
// particle sliding along it (the wall particles diagonally ahead approach it along r_ij) and the
// factor scales exactly that; between fluid particles the factor changes nothing. Laminar viscosity
// and pressures are zero here, so what remains is the artificial term alone.
FluidRates<2> sliding_over_a_wall_row(const PhysicsParams& P, bool multiphase) {
  const FluidMaterial& M = P.materials.fluid[0];
  // i 0.6 dp above the first row of wall particles (spacing dp), sliding along +x at 1 m/s.
  const ParticleState<2> i{{0.2f, 0.006f}, {1.0f, 0.0f}, M.rho0, 0.0f, 0, {0, 0}, {0, 0}};
  FluidRates<2> sum;
  for (int k = -4; k <= 4; ++k)
    for (int layer = 0; layer < 3; ++layer) {
      const ParticleState<2> j{{0.2f + 0.01f * k, -0.005f - 0.01f * layer}, {0.0f, 0.0f}, M.rho0, 0.0f, P.materials.tank(), {0, 0}, {0, 0}};
      add_pair_rates(sum, multiphase ? multiphase_pair_terms<WendlandC2, 2>(P, M, i, j, neighbour_fluid(P, j.material), M.viscosity)
                                     : fluid_pair_terms<WendlandC2, 2>(P, M, i, j));
    }
  return sum;
}

TEST(PairTerms, TheWallFactorScalesTheArtificialFrictionAlongAWall) {
  for (bool multiphase : {false, true}) {
    PhysicsParams P = lattice_params(2, "fluid:\n  viscosity: 0\n  artificial_viscosity: 0.02\n");
    ASSERT_EQ(P.wall_artificial_viscosity, 1.0f) << "the default keeps the friction";
    const FluidRates<2> full = sliding_over_a_wall_row(P, multiphase);
    EXPECT_LT(full.acc[0], -0.1f) << "slowed along the wall";
    P.wall_artificial_viscosity = 0.5f;
    const FluidRates<2> half = sliding_over_a_wall_row(P, multiphase);
    EXPECT_NEAR(half.acc[0], 0.5f * full.acc[0], 1e-5f * std::fabs(full.acc[0]));
    P.wall_artificial_viscosity = 0.0f;
    const FluidRates<2> none = sliding_over_a_wall_row(P, multiphase);
    EXPECT_EQ(none.acc[0], 0.0f);
    EXPECT_EQ(none.acc[1], 0.0f);
  }
}

TEST(PairTerms, TheWallFactorLeavesFluidPairsAlone) {
  PhysicsParams P = lattice_params(2, "fluid:\n  artificial_viscosity: 0.02\n");
  PhysicsParams Q = P;
  Q.wall_artificial_viscosity = 0.0f;
  int fluid_pairs = 0, wall_pairs_changed = 0;
  for_random_pairs(P, [&](const FluidMaterial& M, const ParticleState<2>& i, const ParticleState<2>& j) {
    const bool same = same_bits(fluid_pair_terms<WendlandC2, 2>(P, M, i, j), fluid_pair_terms<WendlandC2, 2>(Q, M, i, j));
    if (P.is_fluid(j.material)) {
      EXPECT_TRUE(same);
      ++fluid_pairs;
    } else {
      wall_pairs_changed += !same;
    }
  });
  EXPECT_GT(fluid_pairs, 1000);
  EXPECT_GT(wall_pairs_changed, 100) << "approaching wall pairs lose their artificial viscosity";
}

}  // namespace
}  // namespace spate
