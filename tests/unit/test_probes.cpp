// Probes (solver/sim/probes.cpp): CSV headers with units, height gauges that follow the surface
// continuously and can ignore spray, a front that follows a bore over a wet bed, the sensor's moving
// average and the points on which a wall-pressure sensor samples the fluid.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "../source_dir.hpp"
#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "sim/probes.hpp"
#include "sim/slab_worker.hpp"
#include "slabs.hpp"

namespace spate {
namespace {

// A 2D tank 0.2 x 0.1 at dp = 0.005, a 0.05 x 0.03 block of water at the left wall.
const char* kTank = R"(name: probes
dimensions: 2
dp: 0.005
time: {end: 0.1}
tank:
  size: [0.2, 0.1]
fluid_blocks:
  - min: [0, 0]
    max: [0.05, 0.03]
probes:
  - {name: level, type: height, position: [0.025]}
  - {name: column, type: height, position: [0.025], connected: true}
  - {name: front, type: front}
  - {name: bore, type: front, min_depth: 0.02}
)";

using Slab = test::OneSlab;

TEST(ProbeFiles, HeadersCarryUnits) {
  ProbeSpec p;
  p.type = ProbeType::Pressure;
  EXPECT_EQ(probe_header(p, 2), "time[s],step,pressure[Pa]");
  p.type = ProbeType::Velocity;
  EXPECT_EQ(probe_header(p, 3), "time[s],step,vx[m/s],vy[m/s],vz[m/s]");
  p.type = ProbeType::Height;
  EXPECT_EQ(probe_header(p, 2), "time[s],step,height[m]");
  p.type = ProbeType::Force;
  EXPECT_EQ(probe_header(p, 2), "time[s],step,fx[N/m],fy[N/m]");  // 2D: per metre of depth
  EXPECT_EQ(probe_header(p, 3), "time[s],step,fx[N],fy[N],fz[N]");
  p.viscous = true;  // then the viscous part
  EXPECT_EQ(probe_header(p, 2), "time[s],step,fx[N/m],fy[N/m],fx_viscous[N/m],fy_viscous[N/m]");
  p.viscous = false;
  p.type = ProbeType::Front;
  EXPECT_EQ(probe_header(p, 3), "time[s],step,front[m]");
  p.type = ProbeType::WallPressure;
  EXPECT_EQ(probe_header(p, 2), "time[s],step,pressure[Pa]");
  p.window = 0.01;  // the averaged reading, then the instantaneous one
  EXPECT_EQ(probe_header(p, 3), "time[s],step,pressure[Pa],pressure_instant[Pa]");
  p.type = ProbeType::Centroid;
  EXPECT_EQ(probe_header(p, 2), "time[s],step,x[m],y[m],vx[m/s],vy[m/s]");
}

// The centroid of a phase: the mean position and velocity of that fluid's particles only, and the
// same on one slab as on three (exact integer sums).
TEST(CentroidProbe, MeanOfOnePhaseIndependentOfTheSplit) {
  const Case c = parse_case(kTank, "probes.yaml",
                            {"fluids=[{name: water}, {name: oil, density: 800}]",
                             "fluid_blocks=[{fluid: oil, min: [0.1, 0], max: [0.2, 0.02]}, {min: [0, 0], max: [0.05, 0.03]}]"});
  ParticleStore p = generate_particles(c);
  for (std::size_t i = 0; i < p.size(); ++i) p.vel[0][i] = p.material[i] == 1 ? 0.5f : -1.0f;
  Slab one(c, p);
  auto row = sample_centroid(one.w, 1);
  ASSERT_EQ(row.size(), 4u);
  EXPECT_NEAR(row[0], 0.15, 1e-6);   // oil: x in [0.1, 0.2]
  EXPECT_NEAR(row[1], 0.01, 1e-6);   //      y in [0, 0.02]
  EXPECT_NEAR(row[2], 0.5, 1e-6);    // its velocity only, not the water's
  EXPECT_NEAR(row[3], 0.0, 1e-12);
  const auto water = sample_centroid(one.w, 0);
  EXPECT_NEAR(water[0], 0.025, 1e-6);
  EXPECT_NEAR(water[2], -1.0, 1e-6);

  test::SplitSlabs three(c, p, 3);
  const auto rows = three.each([](int, SlabWorker& w) { return sample_centroid(w, 1); });
  for (int s = 0; s < 3; ++s) EXPECT_EQ(rows[s], row) << "slab " << s;
}

// Lifting the water by a fraction of the dp/4 sampling step lifts the reading by as much: the
// surface is interpolated between samples, not read off them (no staircase).
TEST(HeightGauge, FollowsTheSurfaceContinuously) {
  const Case c = parse_case(kTank, "probes.yaml");
  const ParticleStore initial = generate_particles(c);
  const double lift = c.dp / 40;  // a tenth of the sampling step
  const PhysicsParams P = physics_params(c);
  std::vector<double> heights;
  for (int k = 0; k <= 10; ++k) {
    ParticleStore p = initial;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (P.is_fluid(p.material[i])) p.pos[1][i] += static_cast<float>(k * lift);
    Slab s(c, p);
    heights.push_back(sample_height(s.w, c.probes[0], c));
  }
  EXPECT_NEAR(heights[0], 0.03, c.dp / 2) << "the block is 0.03 m deep";
  for (int k = 1; k <= 10; ++k)
    EXPECT_NEAR(heights[k] - heights[k - 1], lift, 0.3 * lift) << "lift " << k;
}

// Drops of spray above the water: the highest surface reads them, the connected column does not.
TEST(HeightGauge, ConnectedColumnIgnoresSpray) {
  const Case c = parse_case(kTank, "probes.yaml");
  ParticleStore p = generate_particles(c);
  // A 3 x 3 blob of fluid 3 cm above the surface, over the gauge.
  std::size_t donor = 0;
  while (!physics_params(c).is_fluid(p.material[donor])) ++donor;
  std::uint32_t id = static_cast<std::uint32_t>(p.size());
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      p.append_from(p, donor);
      p.pos[0].back() = static_cast<float>(0.02 + a * c.dp);
      p.pos[1].back() = static_cast<float>(0.06 + b * c.dp);
      p.id.back() = id++;
    }
  p.set_owned(p.size());
  Slab s(c, p);
  EXPECT_NEAR(sample_height(s.w, c.probes[1], c), 0.03, c.dp / 2) << "connected: the water on the floor";
  EXPECT_GT(sample_height(s.w, c.probes[0], c), 0.07) << "highest: the top of the spray";
}

// With a wet bed the fluid reaches the far wall from t = 0; a minimum depth puts the front at the
// edge of the deep water instead.
TEST(FrontProbe, MinimumDepthSkipsTheWetBed) {
  const Case c = parse_case(kTank, "probes.yaml", {"wet_bed=0.01"});
  Slab s(c, generate_particles(c));
  const double far_wall = c.tank_origin[0] + c.tank_size[0];
  EXPECT_NEAR(local_front(s.w, 0, front_level(c.probes[2], c)), far_wall, c.dp) << "no minimum depth: the bed's end";
  EXPECT_NEAR(local_front(s.w, 0, front_level(c.probes[3], c)), 0.05, c.dp) << "min_depth 0.02: the block's edge";
  EXPECT_EQ(front_level(c.probes[2], c), -std::numeric_limits<double>::infinity());
}

TEST(MovingAverage, ZeroWindowPassesSamplesThrough) {
  MovingAverage a(0.0);
  EXPECT_DOUBLE_EQ(a.add(0.0, 3.0), 3.0);
  EXPECT_DOUBLE_EQ(a.add(0.1, -2.0), -2.0);
}

// The mean of the piecewise-linear signal over the trailing window: a ramp v = t averaged over w
// lags it by w/2; before a full window the mean covers what was sampled.
TEST(MovingAverage, RampLagsByHalfTheWindow) {
  MovingAverage a(0.01);
  double last = 0.0;
  for (int k = 0; k <= 100; ++k) {
    const double t = 1e-3 * k + 0.37e-3 * (k % 3);  // uneven sampling
    last = a.add(t, t);
    if (t > 0.0105) {
      EXPECT_NEAR(last, t - 0.005, 1e-12) << t;
    }
    if (k == 2) {
      EXPECT_NEAR(last, 0.5 * t, 1e-12);
    }
  }
  MovingAverage c(0.002);
  for (int k = 0; k < 50; ++k) EXPECT_DOUBLE_EQ(c.add(1e-4 * k, 7.5), 7.5);
}

// The sensor's points lie on its disc (segment in 2D), centred on its position, spaced at most dp/4.
TEST(SensorPoints, CoverTheDiscEvenly) {
  ProbeSpec s;
  s.position = {1.61, 0.003, 0};
  s.normal = {-1, 0, 0};
  s.diameter = 0.0042;
  const auto line = sensor_points(s, 2, 0.005);
  ASSERT_EQ(line.size(), 4u);  // ceil(4.2 / 1.25)
  double mean = 0;
  for (auto& x : line) {
    EXPECT_DOUBLE_EQ(x[0], 1.61);
    EXPECT_LE(std::fabs(x[1] - 0.003), 0.0021);
    mean += x[1] / line.size();
  }
  EXPECT_NEAR(mean, 0.003, 1e-12);
  s.position = {0.89, 0.305, 0.02};
  s.diameter = 0.01;
  const auto disc = sensor_points(s, 3, 0.01);
  ASSERT_GT(disc.size(), 8u);
  Vec3d centre{0, 0, 0};
  for (auto& x : disc) {
    EXPECT_DOUBLE_EQ(x[0], 0.89);
    EXPECT_LE(std::hypot(x[1] - 0.305, x[2] - 0.02), 0.005 + 1e-12);
    for (int k = 0; k < 3; ++k) centre[k] += x[k] / disc.size();
  }
  EXPECT_NEAR(centre[1], 0.305, 1e-12);
  EXPECT_NEAR(centre[2], 0.02, 1e-12);
  s.diameter = 0;
  EXPECT_EQ(sensor_points(s, 3, 0.01).size(), 1u);
}

// The interface probe (issue 35) on the linear Rayleigh-Taylor start: the light fluid below
// y = 0.5 - a0 sin(2 pi x), a0 = 0.0075, less than half of dp = 0.02, placed by the mode's
// displacement (top_wave start: displace). The probe finds the interface to a fraction of dp:
// half its extent is a0 (the rows next to the face move by a0 e^{-k dp/2} = 0.94 a0, and the
// fraction's crossing lies between them and the face), its middle at 0.5. Cut from the lattice
// instead (start: cut), the wave vanishes: every row lies more than a0 from y = 0.5.
TEST(InterfaceProbe, ResolvesAWaveSmallerThanTheSpacing) {
  const std::string file = test::source_dir() + "/cases/rayleigh_taylor_linear_2d.yaml";
  for (const bool displaced : {true, false}) {
    const std::string cut = "fluid_blocks=[{fluid: light, min: [0, 0], max: [1, 0.5], top_wave: {amplitude: -0.0075, wavelength: 1}}, "
                            "{fluid: heavy, min: [0, 0], max: [1, 1]}]";
    const Case c = load_case(file, {displaced ? "output.interval=0" : cut});
    const ParticleStore particles = generate_particles(c);
    Slab s(c, particles);
    const auto [bottom, top] = local_interface_extent(s.w, c, 1);
    if (displaced) {
      EXPECT_NEAR(0.5 * (top - bottom), 0.0075, 0.0075 * 0.1);
      EXPECT_NEAR(0.5 * (top + bottom), 0.5, 0.001);
    } else {
      EXPECT_LT(0.5 * (top - bottom), 0.001);
    }
  }
}

}  // namespace
}  // namespace spate
