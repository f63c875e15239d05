// Relaxation before t = 0 (solver/sim/relax.hpp): a perturbed block of water in a tank settles into a
// distribution where eq. 7's pressure term exerts far less force on a uniform pressure than right
// after the perturbation, without leaving the block (free surface and walls hold), deterministically;
// without a `relax:` section the lattice start is untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "case/case.hpp"
#include "case/generator.hpp"
#include "physics/kernels.hpp"
#include "sim/relax.hpp"

namespace spate {
namespace {

// A 2D tank 0.1 x 0.06 at dp = 0.002, a 0.05 x 0.03 block of water at the left wall (375 particles).
const char* kTank = R"(name: relax
dimensions: 2
dp: 0.002
time: {end: 0.1}
tank:
  size: [0.1, 0.06]
fluid_blocks:
  - min: [0, 0]
    max: [0.05, 0.03]
)";

// RMS over the fluid particles at least 2h inside the block of |sum_j V_j grad_i W_ij| (walls
// included), in units of 1/dp: the force per unit pressure of eq. 7's p_i + p_j.
double interior_imbalance(const Case& c, const ParticleStore& p) {
  const PhysicsParams P = physics_params(c);
  const float margin = 2.0f * P.h;
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.material[i] != 0) continue;
    const float x = p.pos[0][i], y = p.pos[1][i];
    if (x < margin || x > 0.05f - margin || y < margin || y > 0.03f - margin) continue;
    double g[2] = {0, 0};
    for (std::size_t j = 0; j < p.size(); ++j) {
      const float r[2] = {x - p.pos[0][j], y - p.pos[1][j]};
      const float r2 = r[0] * r[0] + r[1] * r[1];
      if (r2 >= P.support2 || j == i) continue;
      const float F = kernel_gradient_factor<WendlandC2>(P, r2);
      for (int a = 0; a < 2; ++a) g[a] += c.dp * c.dp * F * r[a];
    }
    sum += (g[0] * g[0] + g[1] * g[1]) * c.dp * c.dp;
    ++n;
  }
  return std::sqrt(sum / n);
}

TEST(Relax, SettlesAPerturbedBlockWithoutLeavingIt) {
  const Case lattice = parse_case(kTank, "relax.yaml");
  const ParticleStore start = generate_particles(lattice);
  const ParticleStore untouched = relax_particles(lattice, start);
  for (std::size_t i = 0; i < start.size(); ++i) ASSERT_EQ(untouched.pos[0][i], start.pos[0][i]) << "no relax section: the lattice";

  // The perturbed start alone (one iteration at a vanishing rate), and the relaxed one.
  const Case perturbed = parse_case(kTank, "relax.yaml", {"relax.steps=1", "relax.rate=1e-6"});
  const Case relaxed = parse_case(kTank, "relax.yaml", {"relax.steps=400", "relax.rate=0.3"});
  const ParticleStore a = relax_particles(perturbed, start), b = relax_particles(relaxed, start);
  const double before = interior_imbalance(perturbed, a), after = interior_imbalance(relaxed, b);
  std::printf("|sum V grad W| dp, interior RMS: lattice %.2e, perturbed %.3f, relaxed %.3f\n", interior_imbalance(lattice, start), before, after);
  EXPECT_GT(before, 0.05) << "the perturbation (0.2 dp) must unsettle the lattice";
  EXPECT_LT(after, 0.05 * before) << "before " << before << ", after " << after;

  double moved = 0.0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (b.material[i] != 0) {
      EXPECT_EQ(b.pos[0][i], start.pos[0][i]) << "walls stay";
      continue;
    }
    moved = std::max(moved, static_cast<double>(std::hypot(b.pos[0][i] - start.pos[0][i], b.pos[1][i] - start.pos[1][i])));
    EXPECT_GE(b.pos[0][i], 0.0f);
    EXPECT_LE(b.pos[0][i], 0.05f + 0.5f * lattice.dp) << "the free surface holds";
    EXPECT_GE(b.pos[1][i], 0.0f);
    EXPECT_LE(b.pos[1][i], 0.03f + 0.5f * lattice.dp);
  }
  EXPECT_GT(moved, 0.1 * lattice.dp);
  const ParticleStore again = relax_particles(relaxed, start);
  for (std::size_t i = 0; i < b.size(); ++i) ASSERT_EQ(again.pos[1][i], b.pos[1][i]) << "deterministic";
}

}  // namespace
}  // namespace spate
