// A fluid that fills its container (density.closed_volume, solver/sim/closed_volume.cpp): the sum
// of rho0 / rho over its particles is held at its start value by scaling every density once it
// drifts past the tolerance; the sum is the same on one slab as on three; the saved reference
// restores exactly and a bad one is refused; the key is read and refused with a summation density.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "case/case.hpp"
#include "case/generator.hpp"
#include "sim/closed_volume.hpp"
#include "sim/slab_worker.hpp"
#include "slabs.hpp"

namespace spate {
namespace {

// A periodic 2D channel 0.2 x 0.1 at dp = 0.01, full of water, the volume held.
const char* kChannel = R"(name: closed
dimensions: 2
dp: 0.01
time: {end: 0.1}
density: {closed_volume: true}
tank:
  size: [0.2, 0.1]
  open_top: false
  periodic: [x]
fluid_blocks:
  - min: [0, 0]
    max: [0.2, 0.1]
)";

using Slab = test::OneSlab;

// sum rho0 / rho over the fluid, in double.
double volume_sum(SlabWorker& w) {
  const ParticleStore& p = w.particles();
  double s = 0;
  for (std::size_t i = 0; i < p.owned(); ++i)
    if (w.params().is_fluid(p.material[i])) s += 1000.0 / p.density[i];
  return s;
}

TEST(ClosedVolume, ADriftedDensityIsScaledBackAndItsDifferencesKept) {
  const Case c = parse_case(kChannel, "closed.yaml");
  ASSERT_TRUE(c.closed_volume);
  Slab slab(c, generate_particles(c));
  ParticleStore& p = slab.w.particles();
  // A pressure gradient along y (the density 1000 + 2 y/m kg/m^3) at the start.
  for (std::size_t i = 0; i < p.owned(); ++i)
    if (slab.w.params().is_fluid(p.material[i])) p.density[i] = 1000.0f + 20.0f * p.pos[1][i];
  ClosedVolume volume(c);
  volume.start(slab.w);
  const double start = volume_sum(slab.w);
  const std::vector<float> before(p.density.begin(), p.density.begin() + static_cast<std::ptrdiff_t>(p.owned()));

  // A drift below the tolerance (2e-7 of the density) is left alone, to the bit.
  for (std::size_t i = 0; i < p.owned(); ++i)
    if (slab.w.params().is_fluid(p.material[i])) p.density[i] = before[i] * (1.0f + 2e-7f);
  const std::vector<float> small(p.density.begin(), p.density.begin() + static_cast<std::ptrdiff_t>(p.owned()));
  volume.hold(slab.w);
  EXPECT_EQ(volume.scalings(), 0);
  for (std::size_t i = 0; i < p.owned(); ++i) ASSERT_EQ(p.density[i], small[i]) << i;

  // The mean density climbed 3 kg/m^3 (as past the cylinder in 25 s): scaled back to the start's
  // volume, each density's offset from the mean kept to second order (a few 1e-3 kg/m^3 for a jump
  // this large; in a run the scaling acts at 1e-3 kg/m^3).
  for (std::size_t i = 0; i < p.owned(); ++i)
    if (slab.w.params().is_fluid(p.material[i])) p.density[i] = before[i] + 3.0f;
  volume.hold(slab.w);
  EXPECT_EQ(volume.scalings(), 1);
  EXPECT_NEAR(volume_sum(slab.w) / start, 1.0, 2e-6);
  std::size_t fluid = 0;
  for (std::size_t i = 0; i < p.owned(); ++i) {
    if (!slab.w.params().is_fluid(p.material[i])) {
      EXPECT_EQ(p.density[i], before[i]) << "a wall's density is the wall pass's, not scaled";
      continue;
    }
    ++fluid;
    EXPECT_NEAR(p.density[i], before[i], 5e-3) << i;
  }
  EXPECT_GT(fluid, 150u);
}

TEST(ClosedVolume, TheSumIsTheSameOnOneSlabAsOnThree) {
  const Case c = parse_case(kChannel, "closed.yaml");
  ParticleStore p = generate_particles(c);
  for (std::size_t i = 0; i < p.size(); ++i) p.density[i] = 1000.0f + 0.37f * static_cast<float>(i % 11);
  Slab one(c, p);
  const std::int64_t whole = fluid_volume_sum(one.w);
  test::SplitSlabs three(c, p, 3);
  const auto sums = three.each([](int, SlabWorker& w) { return fluid_volume_sum(w); });
  for (int s = 0; s < 3; ++s) EXPECT_EQ(sums[s], whole) << "slab " << s;
}

TEST(ClosedVolume, TheSavedReferenceRestoresAndABadOneIsRefused) {
  const Case c = parse_case(kChannel, "closed.yaml");
  Slab slab(c, generate_particles(c));
  ClosedVolume a(c);
  a.start(slab.w);
  const std::string saved = a.save();
  EXPECT_EQ(saved.rfind("reference ", 0), 0u);
  ClosedVolume b(c);
  b.restore(saved);
  EXPECT_EQ(b.save(), saved);
  EXPECT_THROW(ClosedVolume(c).restore(""), std::runtime_error);
  EXPECT_THROW(ClosedVolume(c).restore("reference -4\n"), std::runtime_error);
  EXPECT_THROW(ClosedVolume(c).restore("reference 12 extra\n"), std::runtime_error);
  const Case open = parse_case(kChannel, "closed.yaml", {"density.closed_volume=false"});
  EXPECT_EQ(ClosedVolume(open).save(), "");
  EXPECT_THROW(ClosedVolume(open).restore(saved), std::runtime_error);
}

TEST(ClosedVolume, TheKeyIsForTheContinuityDensity) {
  EXPECT_FALSE(parse_case(kChannel, "closed.yaml", {"density.closed_volume=false"}).closed_volume);
  try {
    parse_case(kChannel, "closed.yaml", {"density.mode=summation"});
    FAIL() << "a summation density with closed_volume was accepted";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("closed_volume"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace spate
