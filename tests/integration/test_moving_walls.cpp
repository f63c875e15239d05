// Walls that move, against linear water-wave theory (label `validation`): a piston wave maker
// against Biesel's transfer function, and a sloshing tank's free decay and forced response below
// resonance against Faltinsen's linear solution. The resolutions are the shipped cases' (2D,
// coarse where the physics allows: docs/studies/moving-walls.md says why and shows the curves).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "run_helpers.hpp"
#include "wave_theory.hpp"

namespace spate {
namespace {

constexpr double kG = 9.81;

// Runs a sloshing case whose tank stops at `stop` for `free` seconds more; the free oscillations
// at its gauge `wall` from a quarter of the period T1 after the stop (none when the run fails).
test::Waves free_sloshing(const Case& c, const char* scratch, double stop, double free, double T1) {
  const auto out = test::scratch(scratch);
  RunOptions o;
  o.until = stop + free;
  const RunResult r = test::run_case(c, out, o);
  EXPECT_EQ(r.exit_code, 0) << r.message;
  if (r.exit_code != 0) return {};
  return test::zero_up_crossings(test::read_probe(out / "probes" / "wall.csv", 2), stop + 0.25 * T1, stop + free);
}

}  // namespace

// cases/wave_flume_2d.yaml: mean crest-to-trough height of the waves at g1 (x = 2 m) between
// t = 5 s and 11 s within 10 % of Biesel's H = S 2 (cosh 2kd - 1) / (sinh 2kd + 2kd), their mean
// period within 2 % of the piston's. From 5 s the waves at g1 are the piston's steady train (its
// ramp ends at 2.4 s; the group travels the 2 m in 1.8 s); the far wall's reflection arrives after
// 15 s.
TEST(WaveFlume, BieselWaveHeightAndPeriodAtG1) {
  const Case c = load_case(test::case_path("wave_flume_2d.yaml"), {"output.interval=0"});
  const auto out = test::scratch("wave-flume");
  RunOptions o;
  o.until = 11.0;
  const RunResult r = test::run_case(c, out, o);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const MotionSpec& piston = c.motions[0];
  const double stroke = 2.0 * piston.translation[0], omega = piston.omega, period = 2.0 * std::numbers::pi / omega;
  const double depth = c.fluid_blocks[0].max[1];
  const double k = test::wavenumber(omega, depth, kG);
  const double expected = stroke * test::biesel_height_over_stroke(k, depth);
  const test::Waves waves = test::zero_up_crossings(test::read_probe(out / "probes" / "g1.csv", 2), 5.0, 11.0);
  ASSERT_GE(waves.heights.size(), 3u) << "fewer than three waves at g1 between 5 and 11 s";
  const double H = waves.mean_height(), T = waves.mean_period();
  std::printf("wave flume, g1: %zu waves, mean height %.4f m (Biesel %.4f m, %+.1f%%), mean period %.4f s (piston %.4f s, %+.2f%%)\n",
              waves.heights.size(), H, expected, 100 * (H / expected - 1), T, period, 100 * (T / period - 1));
  RecordProperty("height_error", std::to_string(H / expected - 1));
  RecordProperty("period_error", std::to_string(T / period - 1));
  EXPECT_NEAR(H / expected, 1.0, 0.10);
  EXPECT_NEAR(T / period, 1.0, 0.02);
}

// cases/sloshing_2d.yaml forced at the first natural frequency for three periods, then stopped:
// the free oscillation at the wall gauge runs at omega_1^2 = g (pi / L) tanh(pi d / L) within 3 %.
TEST(Sloshing, FreeDecayAtTheFirstNaturalFrequency) {
  const double L = 1.0, d = 0.2;
  const double omega1 = test::sloshing_frequency(1, L, d, kG), T1 = 2.0 * std::numbers::pi / omega1;
  const Case c = load_case(test::case_path("sloshing_2d.yaml"),
                           {"output.interval=0", "tank.motion.period=" + std::to_string(T1), "tank.motion.ramp=" + std::to_string(T1),
                            "tank.motion.end=" + std::to_string(3.5 * T1), "tank.motion.end_ramp=" + std::to_string(0.5 * T1)});
  const test::Waves waves = free_sloshing(c, "sloshing-decay", 3.5 * T1, 4.5 * T1, T1);
  ASSERT_GE(waves.crossings.size(), 4u) << "fewer than three free oscillations";
  const double omega = 2.0 * std::numbers::pi / waves.mean_period();
  std::printf("sloshing free decay: %zu periods, mean height %.4f m, omega %.4f rad/s (theory %.4f, %+.2f%%)\n",
              waves.crossings.size() - 1, waves.mean_height(), omega, omega1, 100 * (omega / omega1 - 1));
  RecordProperty("frequency_error", std::to_string(omega / omega1 - 1));
  EXPECT_GT(waves.mean_height(), 4 * c.dp) << "the tank hardly sloshed: the forcing did not act";
  EXPECT_NEAR(omega / omega1, 1.0, 0.03);
}

// Forced sway below resonance (omega = 0.8 omega_1, A = 0.01 m): the steady amplitude at the wall
// gauge, fitted at the forcing frequency (with the free mode omega_1 that the start excites
// fitted alongside), within 15 % of Faltinsen's linear solution.
TEST(Sloshing, ForcedSwayBelowResonanceMatchesLinearTheory) {
  const double L = 1.0, d = 0.2, A = 0.01, xi = 0.01;
  const double omega1 = test::sloshing_frequency(1, L, d, kG), omega = 0.8 * omega1;
  const double period = 2.0 * std::numbers::pi / omega;
  const Case c = load_case(test::case_path("sloshing_2d.yaml"),
                           {"output.interval=0", "tank.motion.period=" + std::to_string(period), "tank.motion.translation=[" + std::to_string(A) + ", 0]",
                            "tank.motion.ramp=" + std::to_string(2 * period)});
  const auto out = test::scratch("sloshing-forced");
  RunOptions o;
  o.until = 2 * period + 7 * period;
  const RunResult r = test::run_case(c, out, o);
  ASSERT_EQ(r.exit_code, 0) << r.message;
  const auto gauge = test::read_probe(out / "probes" / "wall.csv", 2);
  const auto amplitudes = test::harmonic_amplitudes(gauge, 2 * period + period, o.until.value(), {omega, omega1});
  const double expected = test::sway_response_amplitude(A, omega, L, d, xi, kG);
  std::printf("sloshing forced at 0.8 omega_1: amplitude %.5f m at omega (linear theory %.5f m, %+.1f%%), %.5f m at omega_1\n",
              amplitudes[0], expected, 100 * (amplitudes[0] / expected - 1), amplitudes[1]);
  RecordProperty("amplitude_error", std::to_string(amplitudes[0] / expected - 1));
  EXPECT_NEAR(amplitudes[0] / expected, 1.0, 0.15);
}

// cases/sloshing_circular_2d.yaml: a tank of any shape (here a disc, half full) swayed at its first
// natural frequency for three periods, then stopped: the free oscillation at the wall gauge runs at
// omega_1^2 R / g = 1.3557 (McIver 1989; scripts/studies/circular_canal_modes.py) within 2 %
// (measured -0.14 %; -0.3 % at dp / 2). A box tank of the same area would slosh at 1.33 and one of
// depth R at 1.44: the curved walls are what is tested.
TEST(Sloshing, CircularCanalFreeDecayAtItsFirstFrequency) {
  const double R = 0.2, omega1 = std::sqrt(1.3557 * kG / R), T1 = 2.0 * std::numbers::pi / omega1;
  const Case c = load_case(test::case_path("sloshing_circular_2d.yaml"), {"output.interval=0"});
  ASSERT_NEAR(c.motions[0].omega, omega1, 1e-3 * omega1) << "the case is forced at its first natural frequency";
  const test::Waves waves = free_sloshing(c, "sloshing-circular", 3.0 * T1, 5.0 * T1, T1);
  ASSERT_GE(waves.crossings.size(), 4u) << "fewer than three free oscillations";
  const double omega = 2.0 * std::numbers::pi / waves.mean_period();
  std::printf("circular canal free decay: %zu periods, mean height %.4f m, omega %.4f rad/s (theory %.4f, %+.2f%%)\n",
              waves.crossings.size() - 1, waves.mean_height(), omega, omega1, 100 * (omega / omega1 - 1));
  RecordProperty("frequency_error", std::to_string(omega / omega1 - 1));
  EXPECT_GT(waves.mean_height(), 2 * c.dp) << "the tank hardly sloshed: the forcing did not act";
  EXPECT_NEAR(omega / omega1, 1.0, 0.02);
}

// A time-series motion (a CSV file, natural cubic spline) that samples the sloshing tank's sinusoid
// every 10 ms drives the run as the sinusoid does: over 1 s of sway (+-1 cm, the water at the wall
// rising and falling 2.5 cm) the wall gauge that rides with the tank reads the same heights within
// 0.5 mm (measured: 0.09 mm; the spline's error on the sinusoid is below 1e-7 m, what is left is
// the float rounding of two paths to the same motion, carried by the flow).
TEST(Sloshing, ATimeSeriesMotionDrivesTheTankAsTheSinusoidItSamples) {
  const double A = 0.01, period = 0.8;  // the tank accelerates at up to 0.06 g: no breaking
  const auto dir = test::scratch("sloshing-csv");
  std::filesystem::create_directories(dir);
  const auto csv = dir / "sway.csv";
  {
    std::ofstream f(csv);
    f << "time,x\n";
    f.precision(17);
    for (int k = 0; k <= 120; ++k) f << 0.01 * k << "," << A * std::sin(2.0 * std::numbers::pi * 0.01 * k / period) << "\n";
  }
  // A fixed time step: both runs sample their gauges at the same steps.
  const std::vector<std::string> common = {"output.interval=0", "output.probe_interval=0.01", "dp=0.02", "time.dt=0.0005"};
  auto with = [&](std::vector<std::string> sets) {
    sets.insert(sets.end(), common.begin(), common.end());
    return load_case(test::case_path("sloshing_2d.yaml"), sets);
  };
  const Case sine = with({"tank.motion.ramp=0", "tank.motion.period=" + std::to_string(period), "tank.motion.translation=[" + std::to_string(A) + ", 0]"});
  const Case series = with({"tank.motion={file: " + csv.string() + "}"});
  ASSERT_EQ(series.motions.at(0).file, csv.lexically_normal().string());
  RunOptions o;
  o.until = 1.0;
  std::vector<std::vector<std::pair<double, double>>> gauges;
  for (const Case* c : {&sine, &series}) {
    const auto out = dir / (c == &sine ? "sine" : "series");
    const RunResult r = test::run_case(*c, out, o);
    ASSERT_EQ(r.exit_code, 0) << r.message;
    gauges.push_back(test::read_probe(out / "probes" / "wall.csv", 2));
  }
  ASSERT_EQ(gauges[0].size(), gauges[1].size());
  ASSERT_GE(gauges[0].size(), 50u);
  double largest = 0.0, lo = 1e9, hi = -1e9;
  for (std::size_t k = 0; k < gauges[0].size(); ++k) {
    EXPECT_DOUBLE_EQ(gauges[0][k].first, gauges[1][k].first);
    largest = std::max(largest, std::fabs(gauges[0][k].second - gauges[1][k].second));
    lo = std::min(lo, gauges[0][k].second), hi = std::max(hi, gauges[0][k].second);
  }
  std::printf("sloshing, CSV against sinusoid: gauge range %.4f m, largest difference %.2e m\n", hi - lo, largest);
  EXPECT_GT(hi - lo, 0.01) << "the water at the wall hardly moved: the test cannot tell the motions apart";
  EXPECT_LT(largest, 5e-4);
}

}  // namespace spate
