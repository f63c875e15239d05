// Case loader (solver/case/case_loader.cpp): a valid case parses with its defaults, --set
// overrides any key (nested, new, lists), and every class of bad input is a CaseError that names
// the file, the key and the reason. The program-level behaviour (exit 2, nothing written) is in
// tests/integration.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "case_errors.hpp"
#include "../source_dir.hpp"
#include "case/case.hpp"
#include "physics/density_gradient.hpp"

namespace spate {
namespace {

const char* kMinimal2D = R"(name: tiny
dimensions: 2
dp: 0.01
time:
  end: 0.1
tank:
  size: [0.2, 0.1]
fluid_blocks:
  - min: [0, 0]
    max: [0.05, 0.06]
)";

const char* kFull3D = R"(name: full
dimensions: 3
dp: 0.02
smoothing_ratio: 1.5
kernel: cubic_spline
gravity: [0, 0, -10]
fluid:
  density: 998
  viscosity: 0.002
  sound_speed: 30
  artificial_viscosity: 0.05
  wall_artificial_viscosity: 0.25
  wall_tension: true
  body_force: [0.1, 0, 0]
density:
  mode: summation
  diffusion: molteni_colagrossi
  delta: 0.2
  min_ratio: 0.8
  max_ratio: 1.2
time:
  end: 2
  dt: 1.0e-4
  cfl: 0.3
tank:
  origin: [1, 2, 3]
  size: [1, 0.5, 0.4]
  wall_layers: 2
  open_top: false
  headroom: 0.25
  periodic: [y]
drive:
  mean_velocity: [0, 0.5, 0]
  response_time: 0.2
relaxation_zone:
  min: [1.1, 2.0, 3.0]
  max: [1.3, 2.5, 3.4]
  velocity: [0, 0.5, 0]
  velocity_profile: parabolic
  time: 0.05
fluid_blocks:
  - min: [1, 2, 3]
    max: [1.4, 2.5, 3.2]
    velocity: [0, 0.75, 0]
    velocity_profile: parabolic
wet_bed: 0.04
solids:
  - name: post
    min: [1.6, 2.1, 3]
    max: [1.7, 2.2, 3.4]
    hollow: false
probes:
  - name: p1
    type: pressure
    position: [1.1, 2.2, 3.05]
  - name: gauge
    type: height
    position: [1.2, 2.2]
  - name: load
    type: force
    solid: post
  - name: front
    type: front
    axis: x
output:
  interval: 0.05
  probe_interval: 0.01
  checkpoint_every: 500
decomposition:
  balance_every: 20
)";

using test::error_of;

TEST(CaseLoader, MinimalCaseGetsDefaults) {
  const Case c = parse_case(kMinimal2D, "tiny.yaml");
  EXPECT_EQ(c.file, "tiny.yaml");
  EXPECT_EQ(c.name, "tiny");
  EXPECT_EQ(c.dim, 2);
  EXPECT_DOUBLE_EQ(c.dp, 0.01);
  EXPECT_DOUBLE_EQ(c.smoothing_ratio, 1.3);
  EXPECT_EQ(c.kernel, KernelType::WendlandC2);
  EXPECT_DOUBLE_EQ(c.gravity[0], 0.0);
  EXPECT_DOUBLE_EQ(c.gravity[1], -9.81);  // the last axis is vertical
  EXPECT_DOUBLE_EQ(c.fluids[0].density, 1000.0);
  EXPECT_DOUBLE_EQ(c.fluids[0].viscosity, 1e-3);
  EXPECT_FALSE(c.fluids[0].sound_speed.has_value());
  EXPECT_FALSE(c.fixed_dt.has_value());
  EXPECT_DOUBLE_EQ(c.cfl, 0.2);
  EXPECT_EQ(c.density_mode, DensityMode::Continuity);
  EXPECT_EQ(c.diffusion, DensityDiffusion::Fourtakas);
  EXPECT_EQ(c.flux, MomentumFlux::Central);
  EXPECT_TRUE(c.tension);
  EXPECT_EQ(c.wall_layers, 3);
  EXPECT_TRUE(c.open_top);
  EXPECT_EQ(c.balance_every, 100);
  ASSERT_EQ(c.fluid_blocks.size(), 1u);
  EXPECT_DOUBLE_EQ(c.fluid_blocks[0].max[1], 0.06);
  // Automatic sound speed: 10 sqrt(g H) with H the highest fluid column.
  EXPECT_DOUBLE_EQ(highest_fluid_column(c), 0.06);
  EXPECT_NEAR(sound_speed(c), 10.0 * std::sqrt(9.81 * 0.06), 1e-12);
  const PhysicsParams P = physics_params(c);
  EXPECT_FLOAT_EQ(P.h, 0.013f);
  EXPECT_FLOAT_EQ(P.support2, 4.0f * 0.013f * 0.013f);
  EXPECT_FLOAT_EQ(P.materials.fluid[0].mass, 1000.0f * 0.01f * 0.01f);
  EXPECT_FLOAT_EQ(P.materials.fluid[0].tait_b, P.materials.fluid[0].c0 * P.materials.fluid[0].c0 * 1000.0f / 7.0f);
}

TEST(CaseLoader, AntuonoDiffusionIsReadAndCarriesTheGradientField) {
  const Case c = parse_case(kMinimal2D, "tiny.yaml", {"density.diffusion=antuono"});
  EXPECT_EQ(c.diffusion, DensityDiffusion::Antuono);
  const PhysicsParams P = physics_params(c);
  EXPECT_TRUE(uses_antuono_diffusion(P));
  EXPECT_TRUE(needs_optional_fields(P));
  EXPECT_FALSE(needs_optional_fields(physics_params(parse_case(kMinimal2D, "tiny.yaml"))));
  // Summation density has no diffusion term: nothing runs, nothing is carried.
  const PhysicsParams summation = physics_params(parse_case(kMinimal2D, "tiny.yaml", {"density.diffusion=antuono", "density.mode=summation"}));
  EXPECT_FALSE(uses_antuono_diffusion(summation));
  EXPECT_FALSE(needs_optional_fields(summation));
}

// The impact options of issue 11 (docs/physics.md, "Impact pressures").
TEST(CaseLoader, RiemannAndTensionKeysAreRead) {
  const Case c = parse_case(kMinimal2D, "tiny.yaml",
                            {"density.diffusion=riemann", "momentum.flux=riemann", "momentum.riemann_limiter=2", "fluid.tension=false"});
  EXPECT_EQ(c.diffusion, DensityDiffusion::Riemann);
  EXPECT_EQ(c.flux, MomentumFlux::Riemann);
  EXPECT_DOUBLE_EQ(c.riemann_limiter, 2.0);
  EXPECT_FALSE(c.tension);
  const PhysicsParams P = physics_params(c);
  EXPECT_EQ(P.flux, MomentumFlux::Riemann);
  EXPECT_FLOAT_EQ(P.riemann_limiter, 2.0f);
  EXPECT_FALSE(P.tension);
}

// Particle shifting (delta-plus-SPH; docs/physics.md, "Particle shifting"): off by default.
TEST(CaseLoader, ShiftingKeysAreRead) {
  EXPECT_FALSE(physics_params(parse_case(kMinimal2D, "tiny.yaml")).shifting.enabled);
  const Case c = parse_case(kMinimal2D, "tiny.yaml", {"shifting.enabled=true", "shifting.coefficient=0.5", "shifting.mach=0.14"});
  const PhysicsParams P = physics_params(c);
  EXPECT_TRUE(P.shifting.enabled);
  EXPECT_FLOAT_EQ(P.shifting.coefficient, 0.5f);
  EXPECT_FLOAT_EQ(P.shifting.mach, 0.14f);
  EXPECT_NE(error_of(kMinimal2D, {"shifting.mach=0"}).find("mach"), std::string::npos);
  EXPECT_NE(error_of(kMinimal2D, {"shifting.coefficient=-1"}).find("coefficient"), std::string::npos);
  EXPECT_NE(error_of(kMinimal2D, {"shifting.enabled=true", "shifting.speed=1"}).find("speed"), std::string::npos);
  // The volume-consistent density: off by default, on when asked, and never with a summation density
  // (which follows the positions by itself) or without shifting.
  EXPECT_FALSE(P.shifting.volume_consistent);
  EXPECT_TRUE(physics_params(parse_case(kMinimal2D, "tiny.yaml", {"shifting.enabled=true", "shifting.volume_consistent=true"}))
                  .shifting.volume_consistent);
  EXPECT_FALSE(physics_params(parse_case(kMinimal2D, "tiny.yaml", {"shifting.volume_consistent=true"})).shifting.volume_consistent);
  EXPECT_FALSE(physics_params(parse_case(kMinimal2D, "tiny.yaml",
                                         {"shifting.enabled=true", "shifting.volume_consistent=true", "density.mode=summation"}))
                   .shifting.volume_consistent);
  EXPECT_NE(error_of(kMinimal2D, {"shifting.volume_consistent=2"}).find("volume_consistent"), std::string::npos);
  // The free-surface rules: on by default, off for a closed flow.
  EXPECT_TRUE(P.shifting.free_surface);
  EXPECT_FALSE(physics_params(parse_case(kMinimal2D, "tiny.yaml", {"shifting.enabled=true", "shifting.free_surface=false"}))
                   .shifting.free_surface);
  // The velocity correction: off by default; on when asked, and only then do the stores carry its field.
  EXPECT_FALSE(P.shifting.correct_velocity);
  EXPECT_EQ(optional_field_groups(P) & kShiftVelocity, 0);
  const PhysicsParams corrected = physics_params(parse_case(kMinimal2D, "tiny.yaml", {"shifting.enabled=true", "shifting.correct_velocity=true"}));
  EXPECT_TRUE(corrected.shifting.correct_velocity);
  EXPECT_EQ(optional_field_groups(corrected) & kShiftVelocity, kShiftVelocity);
  EXPECT_FALSE(physics_params(parse_case(kMinimal2D, "tiny.yaml", {"shifting.correct_velocity=true"})).shifting.correct_velocity);
  EXPECT_NE(error_of(kMinimal2D, {"shifting.correct_velocity=yes please"}).find("correct_velocity"), std::string::npos);
}

TEST(CaseLoader, EveryKeyIsRead) {
  const Case c = parse_case(kFull3D, "full.yaml");
  EXPECT_EQ(c.kernel, KernelType::CubicSpline);
  EXPECT_DOUBLE_EQ(c.smoothing_ratio, 1.5);
  EXPECT_DOUBLE_EQ(c.gravity[2], -10.0);
  EXPECT_DOUBLE_EQ(c.fluids[0].density, 998.0);
  EXPECT_DOUBLE_EQ(c.fluids[0].viscosity, 0.002);
  EXPECT_DOUBLE_EQ(sound_speed(c), 30.0);
  EXPECT_DOUBLE_EQ(c.artificial_viscosity, 0.05);
  EXPECT_DOUBLE_EQ(c.wall_artificial_viscosity, 0.25);
  EXPECT_FLOAT_EQ(physics_params(c).wall_artificial_viscosity, 0.25f);
  EXPECT_TRUE(c.wall_tension);
  EXPECT_TRUE(physics_params(c).wall_tension);
  EXPECT_DOUBLE_EQ(c.body_force[0], 0.1);
  EXPECT_EQ(c.density_mode, DensityMode::Summation);
  EXPECT_EQ(c.diffusion, DensityDiffusion::MolteniColagrossi);
  EXPECT_DOUBLE_EQ(c.delta, 0.2);
  EXPECT_DOUBLE_EQ(c.density_min_ratio, 0.8);
  EXPECT_DOUBLE_EQ(c.density_max_ratio, 1.2);
  EXPECT_DOUBLE_EQ(c.end_time, 2.0);
  ASSERT_TRUE(c.fixed_dt.has_value());
  EXPECT_DOUBLE_EQ(*c.fixed_dt, 1e-4);
  EXPECT_DOUBLE_EQ(c.cfl, 0.3);
  EXPECT_DOUBLE_EQ(c.tank_origin[2], 3.0);
  EXPECT_EQ(c.wall_layers, 2);
  EXPECT_FALSE(c.open_top);
  EXPECT_DOUBLE_EQ(c.headroom, 0.25);
  EXPECT_FALSE(c.periodic[0]);
  EXPECT_TRUE(c.periodic[1]);
  EXPECT_TRUE(c.drive.on);
  EXPECT_FALSE(c.drive.axes[0]);
  EXPECT_TRUE(c.drive.axes[1]);
  EXPECT_DOUBLE_EQ(c.drive.mean_velocity[1], 0.5);
  EXPECT_DOUBLE_EQ(c.drive.response_time, 0.2);
  EXPECT_DOUBLE_EQ(c.zone.min[0], 1.1);
  EXPECT_DOUBLE_EQ(c.zone.max[2], 3.4);
  EXPECT_DOUBLE_EQ(c.zone.velocity[1], 0.5);
  EXPECT_TRUE(c.zone.parabolic);
  EXPECT_FLOAT_EQ(physics_params(c).zone.inv_time, 20.0f);
  EXPECT_DOUBLE_EQ(c.fluid_blocks[0].velocity[1], 0.75);
  EXPECT_TRUE(c.fluid_blocks[0].parabolic);
  EXPECT_DOUBLE_EQ(c.wet_bed, 0.04);
  ASSERT_EQ(c.solids.size(), 1u);
  EXPECT_EQ(c.solids[0].name, "post");
  EXPECT_FALSE(c.solids[0].hollow);
  ASSERT_EQ(c.probes.size(), 4u);
  EXPECT_EQ(c.probes[1].type, ProbeType::Height);
  EXPECT_EQ(c.probes[2].solid, "post");
  EXPECT_EQ(c.probes[3].axis, 0);
  EXPECT_DOUBLE_EQ(c.output_interval, 0.05);
  EXPECT_DOUBLE_EQ(c.probe_interval, 0.01);
  EXPECT_EQ(c.checkpoint_every, 500);
  EXPECT_EQ(c.balance_every, 20);
  EXPECT_DOUBLE_EQ(highest_fluid_column(c), 3.2 - 3.0);
}

TEST(CaseLoader, SetOverridesTopLevelNestedAndNewKeys) {
  const Case c = parse_case(kMinimal2D, "tiny.yaml",
                            {"dp=0.005", "fluid.viscosity=0.01", "time.dt=2.5e-5", "tank.size=[0.3, 0.2]",
                             "output.interval=0.02", "kernel=cubic_spline", "fluid_blocks=[{min: [0, 0], max: [0.1, 0.1]}]"});
  EXPECT_DOUBLE_EQ(c.dp, 0.005);
  EXPECT_DOUBLE_EQ(c.fluids[0].viscosity, 0.01);  // `fluid` did not exist: created
  ASSERT_TRUE(c.fixed_dt.has_value());
  EXPECT_DOUBLE_EQ(*c.fixed_dt, 2.5e-5);
  EXPECT_DOUBLE_EQ(c.end_time, 0.1);    // a sibling of the overridden key is kept
  EXPECT_DOUBLE_EQ(c.tank_size[0], 0.3);
  EXPECT_DOUBLE_EQ(c.output_interval, 0.02);
  EXPECT_EQ(c.kernel, KernelType::CubicSpline);
  ASSERT_EQ(c.fluid_blocks.size(), 1u);
  EXPECT_DOUBLE_EQ(c.fluid_blocks[0].max[0], 0.1);
  // The effective case (stored in checkpoints) holds the overrides and parses to the same case.
  const Case again = parse_case(c.source_yaml, "again.yaml");
  EXPECT_DOUBLE_EQ(again.dp, 0.005);
  EXPECT_DOUBLE_EQ(again.fluids[0].viscosity, 0.01);
}

TEST(CaseLoader, SetAutoRestoresAdaptiveValues) {
  const Case c = parse_case(kFull3D, "full.yaml", {"time.dt=auto", "fluid.sound_speed=auto"});
  EXPECT_FALSE(c.fixed_dt.has_value());
  EXPECT_FALSE(c.fluids[0].sound_speed.has_value());
}

// Several fluids: the `fluids` list, blocks and the wet bed naming theirs, disc and wavy blocks.
TEST(CaseLoader, SeveralFluidsAndTheBlocksThatNameThem) {
  const Case c = parse_case(kMinimal2D, "case.yaml",
                            {"fluids=[{name: water}, {name: oil, density: 800, viscosity: 0.05, background_pressure: 10}]",
                             "fluid_blocks=[{fluid: oil, centre: [0.1, 0.05], radius: 0.02}, "
                             "{min: [0, 0], max: [0.2, 0.06], top_wave: {amplitude: 0.01, wavelength: 0.2}}]",
                             "wet_bed={depth: 0.01, fluid: oil}"});
  ASSERT_EQ(c.fluids.size(), 2u);
  EXPECT_EQ(c.fluids[1].name, "oil");
  EXPECT_DOUBLE_EQ(c.fluids[1].density, 800.0);
  EXPECT_DOUBLE_EQ(c.fluids[1].background_pressure, 10.0);
  ASSERT_EQ(c.fluid_blocks.size(), 2u);
  EXPECT_EQ(c.fluid_blocks[0].fluid, 1);
  EXPECT_DOUBLE_EQ(c.fluid_blocks[0].radius, 0.02);
  EXPECT_DOUBLE_EQ(c.fluid_blocks[0].min[0], 0.08);
  EXPECT_EQ(c.fluid_blocks[1].fluid, 0);
  EXPECT_DOUBLE_EQ(c.fluid_blocks[1].wave_amplitude, 0.01);
  EXPECT_EQ(c.wet_bed_fluid, 1);
  EXPECT_DOUBLE_EQ(c.wet_bed, 0.01);
  const PhysicsParams P = physics_params(c);
  EXPECT_EQ(P.materials.fluids, 2);
  EXPECT_TRUE(P.materials.multiphase());
  EXPECT_EQ(P.materials.reference, 0) << "the stiffest fluid (water) gives the walls their density";
  EXPECT_FLOAT_EQ(P.materials.of(1).rho0, 800.0f);
  EXPECT_FALSE(c.fluid_blocks[1].wave_displaces) << "a wavy block is cut from the lattice by default";
  EXPECT_FLOAT_EQ(P.pressure_difference, 0.0f) << "eq. 7's symmetric pressure gradient by default";
}

// Issue 35: the difference form of the pressure gradient and a wave started by its own mode.
TEST(CaseLoader, PressureGradientAndDisplacedWaveAreRead) {
  const Case c = parse_case(kMinimal2D, "case.yaml",
                            {"fluids=[{name: water}, {name: oil, density: 800}]", "momentum.pressure_gradient=difference",
                             "fluid_blocks=[{min: [0, 0], max: [0.2, 0.06], top_wave: {amplitude: 0.01, wavelength: 0.2, start: displace}}]"});
  EXPECT_TRUE(c.pressure_difference);
  EXPECT_FLOAT_EQ(physics_params(c).pressure_difference, 1.0f);
  EXPECT_TRUE(c.fluid_blocks[0].wave_displaces);
  EXPECT_EQ(c.relax_steps, 0) << "no relaxation by default";
  const Case r = parse_case(kMinimal2D, "case.yaml", {"relax={steps: 50, perturbation: 0.1, rate: 0.2}"});
  EXPECT_EQ(r.relax_steps, 50);
  EXPECT_DOUBLE_EQ(r.relax_perturbation, 0.1);
  EXPECT_DOUBLE_EQ(r.relax_rate, 0.2);
}

TEST(CaseLoader, LoadCaseReadsShippedCases) {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::source_dir() + "/cases")) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string name = entry.path().filename().string();
    const Case c = load_case(entry.path().string());
    EXPECT_EQ(c.name + ".yaml", name) << "a shipped case is named after its file";
    EXPECT_TRUE(!c.fluid_blocks.empty() || c.wet_bed > 0) << name << ": no fluid";
    ++n;
  }
  EXPECT_GE(n, 15);
}

// The 3D narrow tank puts the 2D section's sensors at the tank's mid-width, at the same heights, and
// the gated 3D tank its water-level gauges at the 2D gated case's positions, and lifts its gate by
// the same schedule.
void expect_3d_sensors_match_section(const std::string& section, const std::string& narrow_tank, std::vector<std::string> names) {
  const Case flat = load_case(test::source_dir() + "/cases/" + section);
  const Case tank = load_case(test::source_dir() + "/cases/" + narrow_tank);
  ASSERT_EQ(tank.dim, 3) << narrow_tank;
  for (const std::string& name : names) {
    const auto find = [&](const Case& c) {
      return std::find_if(c.probes.begin(), c.probes.end(), [&](const auto& p) { return p.name == name; });
    };
    const auto a = find(flat), b = find(tank);
    ASSERT_NE(a, flat.probes.end()) << section << " " << name;
    ASSERT_NE(b, tank.probes.end()) << narrow_tank << " " << name;
    EXPECT_EQ(b->type, a->type) << name;
    // Along the tank as in the section (the end wall at 1.61 m, which the lattice at dp = 7.5 mm
    // rounds up to 1.6125 m), at mid-width, and a sensor at the section's height.
    EXPECT_NEAR(b->position[0], a->position[0], 0.5 * tank.dp) << narrow_tank << " " << name;
    EXPECT_DOUBLE_EQ(b->position[1], 0.5 * tank.tank_size[1]) << narrow_tank << " " << name;
    if (a->type != ProbeType::Height) EXPECT_DOUBLE_EQ(b->position[2], a->position[1]) << narrow_tank << " " << name;
    EXPECT_DOUBLE_EQ(b->diameter, a->diameter) << narrow_tank << " " << name;
    EXPECT_DOUBLE_EQ(b->window, a->window) << narrow_tank << " " << name;
  }
}

TEST(CaseLoader, LobovskyThreeDimensionalSensorsMatchTheSection) {
  expect_3d_sensors_match_section("dam_break_lobovsky.yaml", "dam_break_lobovsky_3d.yaml", {"p1", "p3", "p4"});
  expect_3d_sensors_match_section("dam_break_lobovsky_gate.yaml", "dam_break_lobovsky_3d_gate.yaml",
                                  {"p1", "p3", "p4", "h1", "h2", "h3", "h4"});
  const Case flat = load_case(test::source_dir() + "/cases/dam_break_lobovsky_gate.yaml");
  const Case tank = load_case(test::source_dir() + "/cases/dam_break_lobovsky_3d_gate.yaml");
  ASSERT_EQ(flat.solids.size(), 1u);
  ASSERT_EQ(tank.solids.size(), 1u);
  const SolidSpec &a = flat.solids[0], &b = tank.solids[0];
  EXPECT_DOUBLE_EQ(b.box.min[0], a.box.min[0]);
  EXPECT_DOUBLE_EQ(b.box.max[0], a.box.max[0]);
  EXPECT_DOUBLE_EQ(b.box.max[2], a.box.max[1]) << "the gate top";
  ASSERT_GE(a.motion, 0);
  ASSERT_GE(b.motion, 0);
  const MotionSpec &lift2 = flat.motions[a.motion], &lift3 = tank.motions[b.motion];
  EXPECT_EQ(lift3.times, lift2.times);
  ASSERT_EQ(lift3.values.size(), lift2.values.size());
  for (std::size_t k = 0; k < lift2.values.size(); ++k) EXPECT_DOUBLE_EQ(lift3.values[k][2], lift2.values[k][1]) << "the lift, sample " << k;
}

// Bad input: each message names the file, the key (with its position where there is one) and why.
struct BadCase {
  const char* what;
  std::vector<std::string> overrides;
  std::vector<std::string> expected;  // substrings of the message
};

TEST(CaseLoader, BadInputIsReportedWithFileKeyAndReason) {
  const std::vector<BadCase> cases = {
      {"dp <= 0", {"dp=0"}, {"case.yaml", "'dp'", "> 0"}},
      {"negative dp", {"dp=-0.01"}, {"'dp'", "> 0"}},
      {"negative density", {"fluid.density=-1000"}, {"'fluid.density'", "> 0"}},
      {"negative viscosity", {"fluid.viscosity=-0.001"}, {"'fluid.viscosity'", ">= 0"}},
      {"wrong type", {"dp=abc"}, {"'dp'", "expected a number", "abc"}},
      {"wrong type integer", {"dimensions=two"}, {"'dimensions'", "integer"}},
      {"wrong type list", {"tank.size=0.2"}, {"'tank.size'", "list of 2 numbers"}},
      {"bad choice", {"kernel=gaussian"}, {"'kernel'", "wendland_c2", "cubic_spline"}},
      {"fluid outside the tank", {"fluid_blocks=[{min: [0, 0], max: [0.3, 0.05]}]"}, {"fluid_blocks[0]", "outside the tank"}},
      {"solid outside the tank", {"solids=[{name: s, min: [0.15, 0], max: [0.25, 0.05]}]"}, {"solids[0]", "outside the tank"}},
      {"fluid overlapping a solid", {"solids=[{name: s, min: [0.04, 0], max: [0.08, 0.05]}]"}, {"solids[0]", "overlaps a fluid block"}},
      {"no fluid at all", {"fluid_blocks=[]"}, {"'fluid_blocks'", "no fluid"}},
      {"unknown top-level key", {"dq=0.01"}, {"'dq'", "unknown key", "did you mean 'dp'"}},
      {"unknown nested key", {"fluid.viscocity=0.001"}, {"'fluid.viscocity'", "unknown key", "did you mean 'fluid.viscosity'"}},
      {"misplaced key", {"viscocity=0.001"}, {"'viscocity'", "unknown key", "did you mean 'fluid.viscosity'"}},
      {"bad --set syntax", {"dp"}, {"--set 'dp'", "key.path=value"}},
      {"--set through a scalar", {"dp.x=1"}, {"--set 'dp.x=1'", "not a map"}},
      {"min above max", {"fluid_blocks=[{min: [0.1, 0], max: [0.05, 0.05]}]"}, {"fluid_blocks[0].max", "greater than min"}},
      {"vertical periodic", {"tank.periodic=[y]"}, {"'tank.periodic'", "vertical"}},
      {"density limits excluding rho0", {"density.max_ratio=0.9"}, {"'density.max_ratio'", "> 1"}},
      {"negative density limit", {"density.min_ratio=-0.5"}, {"'density.min_ratio'", "[0, 1)"}},
      {"negative headroom", {"tank.headroom=-1"}, {"'tank.headroom'", ">= 0"}},
      {"probe defined twice", {"probes=[{name: p, position: [0.01, 0.01]}, {name: p, position: [0.02, 0.01]}]"},
       {"probes[1].name", "defined twice"}},
      {"block of an unknown fluid", {"fluid_blocks=[{fluid: oil, min: [0, 0], max: [0.05, 0.06]}]"},
       {"fluid_blocks[0].fluid", "no fluid named 'oil'", "fluids: water"}},
      {"fluid defined twice", {"fluids=[{name: a}, {name: a}]"}, {"fluids[1].name", "defined twice"}},
      {"fluid without a name", {"fluids=[{density: 800}]"}, {"fluids[0].name", "required"}},
      {"fluid properties beside a fluids list", {"fluids=[{name: a}]", "fluid.density=900"},
       {"'fluid.density'", "each fluid's properties go in its entry"}},
      {"disc block with min", {"fluid_blocks=[{centre: [0.05, 0.05], radius: 0.02, min: [0, 0]}]"},
       {"fluid_blocks[0].min", "'centre' and 'radius' only"}},
      {"wet bed of an unknown fluid", {"wet_bed={depth: 0.02, fluid: air}"}, {"wet_bed.fluid", "no fluid named 'air'"}},
      {"probe on a missing solid", {"probes=[{name: f, type: force, solid: nope}]"}, {"probes[0].solid", "no solid named 'nope'"}},
      {"drive probe without a drive", {"probes=[{name: f, type: drive}]"}, {"probes[0].type", "drive probe", "has none"}},
      {"drive without a periodic axis", {"drive={mean_velocity: [0.1, 0]}"}, {"'drive'", "needs a periodic axis"}},
      {"drive across a wall", {"tank.periodic=[x]", "drive={mean_velocity: [0.1, 0.1]}"}, {"'drive.mean_velocity'", "y component must be 0"}},
      {"drive with a negative response time", {"tank.periodic=[x]", "drive={mean_velocity: [0.1, 0], response_time: -1}"},
       {"'drive.response_time'", ">= 0"}},
      {"relaxation zone without a time", {"relaxation_zone={min: [0, 0], max: [0.05, 0.06], velocity: [0.1, 0]}"},
       {"'relaxation_zone.time'", "required"}},
      {"relaxation zone outside the tank", {"relaxation_zone={min: [0, 0], max: [5, 0.06], velocity: [0.1, 0], time: 0.1}"},
       {"relaxation_zone", "inside the tank"}},
      {"parabolic block without a velocity", {"fluid_blocks=[{min: [0, 0], max: [0.05, 0.06], velocity_profile: parabolic}]"},
       {"fluid_blocks[0].velocity_profile", "needs the block's `velocity`"}},
      {"force on a face that a 2D box has not",
       {"solids=[{name: s, min: [0.15, 0], max: [0.18, 0.05]}]", "probes=[{name: f, type: force, solid: s, face: z+}]"},
       {"probes[0].face", "'z+' is not a face", "x-, x+, y-, y+"}},
      {"wall sensor off every face", {"probes=[{name: s, type: wall_pressure, position: [0.1, 0.05]}]"},
       {"probes[0].position", "must lie on a face"}},
      {"wall sensor on an edge", {"probes=[{name: s, type: wall_pressure, position: [0, 0]}]"}, {"probes[0].position", "edge", "normal"}},
      {"wall sensor facing the wall", {"probes=[{name: s, type: wall_pressure, position: [0, 0.02], normal: [-1, 0]}]"},
       {"probes[0].normal", "is not the normal"}},
      {"wall sensor of negative size", {"probes=[{name: s, type: wall_pressure, position: [0, 0.02], diameter: -1}]"},
       {"probes[0].diameter", ">= 0"}},
      {"wall sensor with a negative window", {"probes=[{name: s, type: wall_pressure, position: [0, 0.02], window: -1}]"},
       {"probes[0].window", ">= 0"}},
      {"unknown momentum flux", {"momentum.flux=upwind"}, {"'momentum.flux'", "central", "riemann"}},
      {"wall factor above one", {"fluid.wall_artificial_viscosity=2"}, {"'fluid.wall_artificial_viscosity'", "between 0 and 1"}},
      {"walls in tension beside a fluid that takes none", {"fluid.tension=false", "fluid.wall_tension=true"},
       {"'fluid.wall_tension'", "tension: false"}},
      {"unknown wall shear", {"tank.wall_shear=rough"}, {"'tank.wall_shear'", "laminar", "log_law"}},
      {"free slip along a periodic axis", {"tank.periodic=[x]", "tank.free_slip=[x]"}, {"'tank.free_slip'", "periodic"}},
      {"free slip along a missing axis", {"tank.free_slip=[z]"}, {"'tank.free_slip'", "'z' is not an axis"}},
      {"surface tension of an unknown fluid", {"fluids=[{name: a}, {name: b}]", "surface_tension=[{between: [a, c], coefficient: 1}]"},
       {"surface_tension[0].between", "no fluid named 'c'", "fluids: a, b"}},
      {"surface tension of a fluid with itself", {"fluids=[{name: a}, {name: b}]", "surface_tension=[{between: [a, a], coefficient: 1}]"},
       {"surface_tension[0].between", "same fluid twice"}},
      {"surface tension of one name", {"fluids=[{name: a}, {name: b}]", "surface_tension=[{between: [a], coefficient: 1}]"},
       {"surface_tension[0].between", "two fluids"}},
      {"surface tension given twice", {"fluids=[{name: a}, {name: b}]",
                                       "surface_tension=[{between: [a, b], coefficient: 1}, {between: [b, a], coefficient: 2}]"},
       {"surface_tension[1].between", "already has a coefficient"}},
      {"negative surface tension", {"fluids=[{name: a}, {name: b}]", "surface_tension=[{between: [a, b], coefficient: -1}]"},
       {"surface_tension[0].coefficient", ">= 0"}},
      {"negative Riemann limiter", {"momentum.riemann_limiter=-1"}, {"'momentum.riemann_limiter'", ">= 0"}},
      {"tension not a boolean", {"fluid.tension=maybe"}, {"'fluid.tension'"}},
      {"negative relaxation", {"relax.steps=-1"}, {"'relax.steps'", "between 0 and 100000"}},
      {"relaxation perturbation too large", {"relax.perturbation=0.8"}, {"'relax.perturbation'", "between 0 and 0.5"}},
      {"relaxation rate zero", {"relax.rate=0"}, {"'relax.rate'", "(0, 1]"}},
      {"unknown pressure gradient", {"momentum.pressure_gradient=upwind"}, {"'momentum.pressure_gradient'", "symmetric", "difference"}},
      {"difference pressure gradient with one fluid", {"momentum.pressure_gradient=difference"},
       {"'momentum.pressure_gradient'", "several fluids"}},
      {"interface probe with one fluid", {"probes=[{name: a, type: interface, phase: water}]"}, {"probes[0].type", "two fluids"}},
      {"interface probe without a phase", {"fluids=[{name: a}, {name: b}]", "probes=[{name: a, type: interface}]"},
       {"probes[0].phase", "required"}},
      {"unknown wave start", {"fluid_blocks=[{min: [0, 0], max: [0.2, 0.06], top_wave: {amplitude: 0.01, wavelength: 0.2, start: bend}}]"},
       {"top_wave.start", "'cut' or 'displace'"}},
      {"displaced wave beyond the linear range",
       {"fluid_blocks=[{min: [0, 0], max: [0.2, 0.06], top_wave: {amplitude: 0.02, wavelength: 0.2, start: displace}}]"},
       {"top_wave.amplitude", "0.05 wavelengths"}},
  };
  for (const BadCase& b : cases) {
    const std::string message = error_of(kMinimal2D, b.overrides);
    for (const std::string& part : b.expected)
      EXPECT_NE(message.find(part), std::string::npos) << b.what << ": '" << part << "' not in: " << message;
  }
}

// A wall sensor takes the normal of the face it lies on (pointing into the fluid; for a solid, out of
// it) and is moved onto the face the particles make when the case puts it within dp/2 of it.
TEST(CaseLoader, WallSensorFindsItsFace) {
  const Case c = parse_case(kMinimal2D, "case.yaml",
                            {"solids=[{name: s, min: [0.15, 0], max: [0.18, 0.05]}]",
                             "probes=[{name: end, type: wall_pressure, position: [0.2004, 0.03], diameter: 0.004, window: 0.001},"
                             " {name: floor, type: wall_pressure, position: [0.1, 0]}, {name: solid, type: wall_pressure, position: [0.15, 0.02]},"
                             " {name: top, type: wall_pressure, position: [0.15, 0.05], normal: [0, 2]}, {name: f, type: force, solid: s, face: x-}]"});
  ASSERT_EQ(c.probes.size(), 5u);
  EXPECT_EQ(c.probes[0].type, ProbeType::WallPressure);
  EXPECT_DOUBLE_EQ(c.probes[0].position[0], 0.2);
  EXPECT_DOUBLE_EQ(c.probes[0].normal[0], -1.0);
  EXPECT_DOUBLE_EQ(c.probes[0].diameter, 0.004);
  EXPECT_DOUBLE_EQ(c.probes[0].window, 0.001);
  EXPECT_DOUBLE_EQ(c.probes[1].normal[1], 1.0);
  EXPECT_DOUBLE_EQ(c.probes[2].normal[0], -1.0);
  EXPECT_DOUBLE_EQ(c.probes[3].normal[1], 1.0);  // the corner of the solid, resolved by the normal
  EXPECT_EQ(c.probes[4].face, 0);
}

// Surface tension and free-slip walls reach the physics constants: sigma symmetric per pair, the
// largest per fluid, the pass switched on; the free-slip axes and the tank's fluid region.
TEST(CaseLoader, SurfaceTensionAndFreeSlipReachThePhysics) {
  const Case c = parse_case(kMinimal2D, "tiny.yaml",
                            {"fluids=[{name: a}, {name: b, density: 100}, {name: c}]",
                             "surface_tension=[{between: [b, a], coefficient: 2.5}, {between: [c, a], coefficient: 1}]",
                             "tank.free_slip=[x]", "tank.wall_shear=log_law"});
  const PhysicsParams P = physics_params(c);
  EXPECT_EQ(P.wall_shear, WallShear::LogLaw);
  EXPECT_TRUE(P.surface_tension.on);
  EXPECT_EQ(P.surface_tension.sigma[0][1], 2.5f);
  EXPECT_EQ(P.surface_tension.sigma[1][0], 2.5f);
  EXPECT_EQ(P.surface_tension.sigma[0][2], 1.0f);
  EXPECT_EQ(P.surface_tension.sigma[1][2], 0.0f);
  EXPECT_EQ(P.surface_tension.largest[0], 2.5f);
  EXPECT_EQ(P.surface_tension.largest[2], 1.0f);
  EXPECT_EQ(P.free_slip_axes, 1u);
  EXPECT_FLOAT_EQ(P.tank_hi[0], 0.2f);
  const PhysicsParams plain = physics_params(parse_case(kMinimal2D, "tiny.yaml", {}));
  EXPECT_FALSE(plain.surface_tension.on);
  EXPECT_EQ(plain.free_slip_axes, 0u);
  EXPECT_EQ(plain.wall_shear, WallShear::Laminar);
}

TEST(CaseLoader, MissingRequiredKeys) {
  std::string no_dp = kMinimal2D;
  no_dp.erase(no_dp.find("dp: 0.01\n"), 9);
  const std::string m = error_of(no_dp);
  EXPECT_NE(m.find("'dp'"), std::string::npos) << m;
  EXPECT_NE(m.find("required"), std::string::npos) << m;
  std::string no_time = kMinimal2D;
  no_time.erase(no_time.find("time:\n  end: 0.1\n"), 17);
  EXPECT_NE(error_of(no_time).find("'time'"), std::string::npos) << error_of(no_time);
  std::string no_tank = kMinimal2D;
  no_tank.erase(no_tank.find("tank:\n  size: [0.2, 0.1]\n"), 26);
  EXPECT_NE(error_of(no_tank).find("'tank'"), std::string::npos) << error_of(no_tank);
}

TEST(CaseLoader, SyntaxErrorGivesLineAndColumn) {
  const std::string broken = "name: x\ndp: 0.01\ntank:\n  size: [0.2, 0.1\ntime: {end: 1}\n";
  const std::string m = error_of(broken);
  EXPECT_EQ(m.rfind("case.yaml:", 0), 0u) << m;
  EXPECT_NE(m.find("YAML syntax error"), std::string::npos) << m;
  // file:line:column with numbers.
  EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(m[std::string("case.yaml:").size()]))) << m;
}

TEST(CaseLoader, ValueErrorsPointAtTheLine) {
  std::string bad = kMinimal2D;
  bad.replace(bad.find("dp: 0.01"), 8, "dp: -0.01");
  const std::string m = error_of(bad);
  EXPECT_EQ(m.rfind("case.yaml:3:", 0), 0u) << m;  // dp is on line 3
}

TEST(CaseLoader, UnreadableFile) {
  try {
    load_case("/nonexistent/spate/case.yaml");
    FAIL() << "no error";
  } catch (const CaseError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("/nonexistent/spate/case.yaml"), std::string::npos) << m;
    EXPECT_NE(m.find("cannot read"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace spate
