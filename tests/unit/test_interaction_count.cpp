// The interaction counter behind `spate bench` against a brute-force count over all particle
// pairs: every pair (i, j), j != i, within the support that a neighbour pass evaluates, i.e.
// fluid i with any j (fluid rates), wall i with fluid j (wall state), and the fluid pairs again
// when the density comes from mass summation.
#include <gtest/gtest.h>

#include <string>
#include <thread>
#include <vector>

#include "../source_dir.hpp"
#include "backend/cpu/interaction_count.hpp"
#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "particles/particle_access.hpp"
#include "sim/slab_worker.hpp"

namespace spate {
namespace {

Case load_case_file(const std::string& name, const std::vector<std::string>& overrides = {}) {
  return load_case(test::source_dir() + "/cases/" + name, overrides);
}

// Sum of the per-slab counts after prepare() on `slabs` in-process slabs.
cpu::InteractionCounts count_on_slabs(const Case& c, int slabs) {
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  const ParticleStore initial = generate_particles(c);
  InProcessHub hub(slabs);
  std::vector<cpu::InteractionCounts> per_slab(slabs);
  auto body = [&](int s) {
    auto t = hub.endpoint(s, L.periodic[0]);
    SlabWorker w(L, P, *t);
    w.take_share(initial, SlabLayout::uniform(L.cells[0], slabs));
    w.prepare(false);
    per_slab[s] = cpu::count_interactions(w.particles(), w.grid(), w.params());
  };
  std::vector<std::thread> pool;
  for (int s = 0; s < slabs; ++s) pool.emplace_back(body, s);
  for (auto& th : pool) th.join();
  cpu::InteractionCounts sum;
  for (const auto& n : per_slab) {
    sum.fluid += n.fluid;
    sum.wall += n.wall;
    sum.summation += n.summation;
  }
  return sum;
}

// All pairs of one slab holding everything (owned particles and their periodic images), no grid.
template <int Dim>
cpu::InteractionCounts brute_force(const Case& c) {
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  InProcessHub hub(1);
  auto t = hub.endpoint(0, L.periodic[0]);
  SlabWorker w(L, P, *t);
  w.take_share(generate_particles(c), SlabLayout::uniform(L.cells[0], 1));
  w.prepare(false);
  const ParticleStore& p = w.particles();
  cpu::InteractionCounts n;
  for (std::size_t i = 0; i < p.owned(); ++i) {
    const Vec<Dim> xi = load_vec<Dim>(p.pos, i);
    for (std::size_t j = 0; j < p.size(); ++j) {
      if (j == i || distance_squared<Dim>(xi, p.pos, j) >= P.support2) continue;
      if (P.is_fluid(p.material[i])) ++n.fluid;
      else if (P.is_fluid(p.material[j])) ++n.wall;
    }
  }
  if (P.density_mode == DensityMode::Summation) n.summation = n.fluid;
  return n;
}

void expect_equal(const cpu::InteractionCounts& a, const cpu::InteractionCounts& b) {
  EXPECT_EQ(a.fluid, b.fluid);
  EXPECT_EQ(a.wall, b.wall);
  EXPECT_EQ(a.summation, b.summation);
  EXPECT_EQ(a.total(), b.total());
}

}  // namespace

TEST(InteractionCount, MatchesBruteForceIn3D) {
  const Case c = load_case_file("hydrostatic_3d.yaml");
  const auto expected = brute_force<3>(c);
  // Sanity: a 3D lattice at h = 1.3 dp has dozens of neighbours per fluid particle, and walls see fluid.
  EXPECT_GT(expected.fluid, 30 * 1152);
  EXPECT_GT(expected.wall, 0);
  EXPECT_EQ(expected.summation, 0);
  expect_equal(count_on_slabs(c, 1), expected);
}

TEST(InteractionCount, MatchesBruteForceIn2DOnAnySplit) {
  const Case c = load_case_file("dam_break_2d.yaml", {"tank.size=[0.16, 0.12]"});
  const auto expected = brute_force<2>(c);
  expect_equal(count_on_slabs(c, 1), expected);
  expect_equal(count_on_slabs(c, 3), expected);
}

TEST(InteractionCount, CountsPeriodicImagesAndSummationPasses) {
  // Poiseuille: periodic along x, so pairs across the boundary go through ghost images.
  const Case c = load_case_file("poiseuille_2d.yaml", {"density.mode=summation"});
  const auto expected = brute_force<2>(c);
  EXPECT_EQ(expected.summation, expected.fluid);
  expect_equal(count_on_slabs(c, 1), expected);
  expect_equal(count_on_slabs(c, 2), expected);
}

}  // namespace spate
