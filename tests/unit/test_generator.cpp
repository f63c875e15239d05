// Particle generator (solver/case/generator.cpp): counts of a small tank worked out by hand, wall
// layers, open/closed top, hollow solids, the wet bed around solids, and no two particles on one
// site.
#include <gtest/gtest.h>

#include "../source_dir.hpp"

#include <chrono>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "case/case.hpp"
#include "case/generator.hpp"
#include "physics/eos.hpp"

namespace spate {
namespace {

// One fluid: the material numbering of physics/materials.hpp.
constexpr std::uint8_t kFluidMaterial = 0, kTankMaterial = 1, kFirstSolidMaterial = 2;

// 2D tank 0.1 x 0.05 at dp = 0.01: 10 x 5 interior sites.
const char* kSmallTank = R"(name: small
dimensions: 2
dp: 0.01
time: {end: 0.1}
tank:
  size: [0.1, 0.05]
  wall_layers: 3
fluid_blocks:
  - min: [0, 0]
    max: [0.05, 0.03]
)";

// 2D tank 0.2 x 0.1, a solid box 6 x 6 sites on the floor at x in [0.10, 0.16].
const char* kSolidTank = R"(name: solid
dimensions: 2
dp: 0.01
time: {end: 0.1}
tank:
  size: [0.2, 0.1]
  wall_layers: 2
wet_bed: 0.03
solids:
  - name: block
    min: [0.10, 0.0]
    max: [0.16, 0.06]
)";

std::map<std::uint8_t, std::int64_t> kinds(const ParticleStore& p) {
  std::map<std::uint8_t, std::int64_t> n;
  for (auto k : p.material) ++n[k];
  return n;
}

// Lattice site index of every particle; each site holds at most one particle.
void expect_distinct_sites(const ParticleStore& p, double dp, const Vec3d& origin) {
  std::set<std::tuple<long, long, long>> sites;
  for (std::size_t i = 0; i < p.size(); ++i) {
    long idx[3] = {0, 0, 0};
    for (int a = 0; a < p.dim(); ++a) {
      const double s = (p.pos[a][i] - origin[a]) / dp - 0.5;
      idx[a] = std::lround(s);
      EXPECT_NEAR(s, static_cast<double>(idx[a]), 1e-3) << "particle " << i << " is off the lattice";
    }
    EXPECT_TRUE(sites.insert({idx[0], idx[1], idx[2]}).second) << "two particles on site of particle " << i;
  }
}

TEST(Generator, SmallTankCountsOpenTop) {
  const Case c = parse_case(kSmallTank, "small.yaml");
  const ParticleCounts n = count_particles(c);
  EXPECT_EQ(n.fluid, 5 * 3);
  // Sites x in [-3, 13), y in [-3, 5) (no lid): 16 x 8, minus the 10 x 5 interior.
  EXPECT_EQ(n.wall, 16 * 8 - 10 * 5);
  const ParticleStore p = generate_particles(c);
  ASSERT_EQ(static_cast<std::int64_t>(p.size()), n.total());
  EXPECT_EQ(p.owned(), p.size());
  auto k = kinds(p);
  EXPECT_EQ(k[kFluidMaterial], n.fluid);
  EXPECT_EQ(k[kTankMaterial], n.wall);
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_EQ(p.id[i], i);
  expect_distinct_sites(p, c.dp, c.tank_origin);
}

TEST(Generator, ClosedTopAndWallLayers) {
  for (int layers = 1; layers <= 4; ++layers) {
    const Case c = parse_case(kSmallTank, "small.yaml",
                              {"tank.open_top=false", "tank.wall_layers=" + std::to_string(layers)});
    const std::int64_t nx = 10 + 2 * layers, ny = 5 + 2 * layers;
    EXPECT_EQ(count_particles(c).wall, nx * ny - 10 * 5) << layers << " layers";
  }
}

TEST(Generator, ThreeDimensionalTank) {
  const Case c = parse_case(kSmallTank, "small3d.yaml",
                            {"dimensions=3", "tank.size=[0.1, 0.04, 0.05]", "tank.wall_layers=2",
                             "fluid_blocks=[{min: [0, 0, 0], max: [0.05, 0.04, 0.03]}]"});
  const ParticleCounts n = count_particles(c);
  EXPECT_EQ(n.fluid, 5 * 4 * 3);
  EXPECT_EQ(n.wall, 14 * 8 * 7 - 10 * 4 * 5);  // open top: z sites [-2, 5)
  const ParticleStore p = generate_particles(c);
  expect_distinct_sites(p, c.dp, c.tank_origin);
}

TEST(Generator, WallParticlesSurroundTheInteriorOnly) {
  const Case c = parse_case(kSmallTank, "small.yaml");
  const ParticleStore p = generate_particles(c);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const bool inside = p.pos[0][i] > 0 && p.pos[0][i] < 0.1f && p.pos[1][i] > 0;
    if (p.material[i] == kFluidMaterial) {
      EXPECT_TRUE(inside) << "fluid particle " << i << " in the wall";
      EXPECT_LE(p.pos[0][i], 0.05f);
      EXPECT_LE(p.pos[1][i], 0.03f);
    } else {
      EXPECT_FALSE(inside) << "wall particle " << i << " inside the tank";
      EXPECT_GT(p.pos[0][i], -0.03f);
      EXPECT_LT(p.pos[0][i], 0.13f);
      EXPECT_GT(p.pos[1][i], -0.03f);
    }
  }
}

TEST(Generator, FluidFillingTheTankNeverOverlapsWallSites) {
  const Case c = parse_case(kSmallTank, "full.yaml", {"fluid_blocks=[{min: [0, 0], max: [0.1, 0.05]}]", "tank.open_top=false"});
  const ParticleCounts n = count_particles(c);
  EXPECT_EQ(n.fluid, 10 * 5);
  EXPECT_EQ(n.wall, 16 * 11 - 10 * 5);
  expect_distinct_sites(generate_particles(c), c.dp, c.tank_origin);
}

TEST(Generator, HollowSolidKeepsWallLayersUnderItsFluidFaces) {
  const Case c = parse_case(kSolidTank, "solid.yaml");
  const ParticleStore p = generate_particles(c);
  auto k = kinds(p);
  // 6 x 6 sites in the box; the 2 x 4 sites deeper than 2 dp from the sides and top (the floor face
  // does not count) are left empty.
  EXPECT_EQ(k[kFirstSolidMaterial], 36 - 8);
  // Wet bed: 3 rows of 20 sites, minus the 6 x 3 sites inside the solid (filled or hollow).
  EXPECT_EQ(k[kFluidMaterial], 60 - 18);
  EXPECT_EQ(k[kTankMaterial], 24 * 12 - 20 * 10);
  expect_distinct_sites(p, c.dp, c.tank_origin);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.material[i] != kFluidMaterial) continue;
    const bool in_solid = p.pos[0][i] > 0.10f && p.pos[0][i] < 0.16f && p.pos[1][i] < 0.06f;
    EXPECT_FALSE(in_solid) << "wet-bed particle " << i << " inside the solid";
  }
}

TEST(Generator, FilledSolid) {
  const Case c = parse_case(kSolidTank, "solid.yaml", {"solids=[{name: block, min: [0.10, 0.0], max: [0.16, 0.06], hollow: false}]"});
  EXPECT_EQ(kinds(generate_particles(c))[kFirstSolidMaterial], 36);
}

TEST(Generator, HydrostaticInitialDensity) {
  const Case c = parse_case(kSmallTank, "small.yaml");
  const ParticleStore p = generate_particles(c);
  const PhysicsParams P = physics_params(c);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.material[i] != kFluidMaterial) {
      EXPECT_EQ(p.density[i], P.materials.fluid[0].rho0);
      continue;
    }
    const double depth = 0.03 - p.pos[1][i];
    const double pressure = tait_pressure(p.density[i], P.materials.fluid[0]);
    EXPECT_NEAR(pressure, 1000.0 * 9.81 * depth, 0.02 * 1000.0 * 9.81 * 0.03) << "particle " << i;
  }
}

// A background pressure is added to the hydrostatic one, as the EOS adds it (eq. 9): the particles
// at the free surface start at rho0 and p_b, and without gravity every particle does (a closed,
// driven channel). Before 2026-12-05 they started at p = 0, i.e. at the density below rho0 that
// cancels p_b, and the continuity equation kept the offset: p_b did not raise the pressure at all.
TEST(Generator, BackgroundPressureIsWhereTheFluidStarts) {
  for (const double g : {9.81, 0.0}) {
    const Case c = parse_case(std::string(kSmallTank) + "gravity: [0, " + std::to_string(-g) + "]\nfluid: {background_pressure: 200}\n",
                              "small.yaml");
    const ParticleStore p = generate_particles(c);
    const PhysicsParams P = physics_params(c);
    const FluidMaterial& m = P.materials.fluid[0];
    ASSERT_EQ(m.background_pressure, 200.0f);
    int top_row = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.material[i] != kFluidMaterial) continue;
      const double depth = 0.03 - p.pos[1][i];
      EXPECT_NEAR(tait_pressure(p.density[i], m), 200.0 + 1000.0 * g * depth, 0.01 * 200.0) << "particle " << i << ", g " << g;
      if (g == 0.0) EXPECT_NEAR(p.density[i], m.rho0, 1e-3f) << "particle " << i;
      top_row += depth < 0.01;
    }
    EXPECT_GT(top_row, 0);
  }
}

TEST(Generator, ZeroFluidParticlesIsBadInput) {
  // A block thinner than half a spacing holds no site centre.
  const Case c = parse_case(kSmallTank, "thin.yaml", {"fluid_blocks=[{min: [0.001, 0], max: [0.004, 0.03]}]"});
  EXPECT_EQ(count_particles(c).fluid, 0);
  EXPECT_THROW(generate_particles(c), CaseError);
}

TEST(Generator, LatticeCoversEveryParticle) {
  for (const char* text : {kSmallTank, kSolidTank}) {
    const Case c = parse_case(text, "case.yaml");
    const Lattice L = make_lattice(c);
    const ParticleStore p = generate_particles(c);
    for (int a = 0; a < c.dim; ++a) {
      EXPECT_GE(L.cell_size[a], 2.0f * 1.3f * 0.01f);
      for (std::size_t i = 0; i < p.size(); ++i) {
        const int cell = L.cell_of(p.pos[a][i], a);
        // Never the outermost cell: a slab there would have no room for its halo.
        EXPECT_GE(cell, 1);
        EXPECT_LE(cell, L.cells[a] - 2);
      }
    }
  }
}

// The closed-form counts equal the generator's site loop on random tanks: 2D and 3D, odd origins
// and spacings, overlapping fluid blocks, hollow and filled solids (also overlapping each other and
// the wet bed), periodic axes and closed tops.
TEST(Generator, ClosedFormCountsEqualTheSiteLoop) {
  std::mt19937 rng(20240607);
  auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  auto box_in = [&](const Case& c, double fill) {
    Box b;
    for (int a = 0; a < c.dim; ++a) {
      const double lo = c.tank_origin[a] + uniform(-0.1, 0.8) * c.tank_size[a];
      b.min[a] = lo;
      b.max[a] = std::min(lo + uniform(0.05, fill) * c.tank_size[a], c.tank_origin[a] + c.tank_size[a] * 1.05);
    }
    return b;
  };
  for (int trial = 0; trial < 300; ++trial) {
    Case c;
    c.dim = trial % 3 == 0 ? 3 : 2;
    c.dp = uniform(0.007, 0.013);
    c.wall_layers = 1 + static_cast<int>(rng() % 4);
    c.open_top = rng() % 2;
    for (int a = 0; a < c.dim; ++a) {
      c.tank_origin[a] = uniform(-0.3, 0.3);
      c.tank_size[a] = uniform(0.05, c.dim == 3 ? 0.15 : 0.3);
    }
    if (rng() % 4 == 0) c.periodic[0] = true;
    for (int k = 0, blocks = static_cast<int>(rng() % 4); k < blocks; ++k) c.fluid_blocks.push_back(FluidBlock{box_in(c, 0.7)});
    for (int k = 0, solids = static_cast<int>(rng() % 4); k < solids; ++k)
      c.solids.push_back(SolidSpec{"s" + std::to_string(k), box_in(c, 0.6), rng() % 2 == 0});
    c.wet_bed = rng() % 3 == 0 ? uniform(0.0, 0.5) * c.tank_size[c.dim - 1] : 0.0;
    const ParticleCounts n = count_particles(c);
    std::int64_t fluid = 0, wall = 0;
    if (n.fluid == 0) {
      EXPECT_THROW(generate_particles(c), CaseError) << "trial " << trial;
      continue;
    }
    const ParticleStore p = generate_particles(c);  // throws if its site loop counts differently
    for (auto k : p.material) (physics_params(c).materials.is_fluid(k) ? fluid : wall)++;
    EXPECT_EQ(fluid, n.fluid) << "trial " << trial;
    EXPECT_EQ(wall, n.wall) << "trial " << trial;
  }
}

// The counts of the paper's case at a spacing of billions of particles come without visiting the
// sites (spate info on the column case at dp = 0.0002 m).
TEST(Generator, CountsAtAnySpacingAreImmediate) {
  const Case coarse = load_case(test::source_dir() + "/cases/dam_break_column_3d.yaml", {"dp=0.01"});
  const ParticleCounts ref = count_particles(coarse);
  const ParticleStore p = generate_particles(coarse);
  EXPECT_EQ(static_cast<std::int64_t>(p.size()), ref.total());
  const auto t0 = std::chrono::steady_clock::now();
  const Case fine = load_case(test::source_dir() + "/cases/dam_break_column_3d.yaml", {"dp=0.0002"});
  const ParticleCounts n = count_particles(fine);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GT(n.total(), 1'000'000'000);
  // Volume scaling from the coarse case: 50^3 times the sites, within the walls' share.
  EXPECT_NEAR(static_cast<double>(n.fluid) / ref.fluid, 125000.0, 0.05 * 125000.0);
  EXPECT_LT(seconds, 1.0);  // a sanity bound on an algorithm that used to take minutes, not a benchmark
}

}  // namespace
}  // namespace spate
