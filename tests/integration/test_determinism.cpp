// Bitwise reproducibility: restart and thread count must not change a single bit.
#include <gtest/gtest.h>

#include <cmath>

#include "backend/cpu/parallel.hpp"
#include "case/motion.hpp"
#include "run_helpers.hpp"

namespace spate {
namespace {

TEST(Restart, ContinuesBitIdentically) {
  const Case c = load_case(test::case_path("dam_break_2d.yaml"), {"output.interval=0", "probes=[]"});
  const auto straight = test::scratch("restart-straight"), first = test::scratch("restart-first"),
             second = test::scratch("restart-second");
  RunOptions o;
  o.steps = 200;
  const RunResult a = test::run_case(c, straight, o);
  o.steps = 100;
  const RunResult b = test::run_case(c, first, o);
  o.restart = b.last_checkpoint;
  const RunResult d = test::run_case(c, second, o);
  ASSERT_EQ(a.final_step, 200);
  ASSERT_EQ(d.final_step, 200);
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(a.last_checkpoint, d.last_checkpoint, &why)) << why;
  EXPECT_EQ(a.simulated_time, d.simulated_time);
}

// A wall sensor's moving average carries over a restart in the same output folder: the sensor
// re-reads its last window of samples from its file, so the file is the one an uninterrupted run
// writes (to the 9 digits the file keeps of the samples it re-reads).
TEST(Restart, SensorAverageContinues) {
  const Case c = load_case(test::case_path("dam_break_2d.yaml"),
                           {"output.interval=0", "output.probe_interval=0",
                            "probes=[{name: wall, type: wall_pressure, position: [0, 0.01], diameter: 0.004, window: 0.001}]"});
  const auto straight = test::scratch("sensor-straight"), resumed = test::scratch("sensor-resumed");
  RunOptions o;
  o.steps = 120;
  test::run_case(c, straight, o);
  o.steps = 60;
  const RunResult b = test::run_case(c, resumed, o);
  o.restart = b.last_checkpoint;
  test::run_case(c, resumed, o);
  for (int col : {0, 2, 3}) {
    const auto a = test::read_probe(straight / "probes" / "wall.csv", col);
    const auto r = test::read_probe(resumed / "probes" / "wall.csv", col);
    ASSERT_EQ(a.size(), 121u);
    ASSERT_EQ(r.size(), a.size());
    for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k].second, r[k].second, 1e-7 * std::fabs(a[k].second)) << k;
  }
}

// Checkpoints written before the field registry (format version 1, tests/fixtures/README.md) still
// restart, and continue bit-identically to a straight run of this build.
TEST(Restart, ReadsFormatVersionOneBitIdentically) {
  const std::filesystem::path fixture = test::source_dir() + "/tests/fixtures/checkpoint_v1_tiny_2d_step10.h5";
  ParticleStore p;
  const CheckpointMeta meta = read_checkpoint(fixture, p);
  ASSERT_EQ(meta.format_version, 1);
  ASSERT_EQ(meta.step, 10);
  const Case c = load_case(test::source_dir() + "/tests/cases/tiny_2d.yaml");
  RunOptions o;
  o.steps = 20;
  const RunResult straight = test::run_case(c, test::scratch("v1-straight"), o);
  o.steps = 10;
  o.restart = fixture;
  const RunResult resumed = test::run_case(c, test::scratch("v1-resumed"), o);
  ASSERT_EQ(resumed.final_step, 20);
  ParticleStore q;
  EXPECT_EQ(read_checkpoint(resumed.last_checkpoint, q).format_version, kCheckpointFormatVersion);
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(straight.last_checkpoint, resumed.last_checkpoint, &why)) << why;
  EXPECT_EQ(straight.simulated_time, resumed.simulated_time);
}

// A steered run of 120 steps replaying `log` (its changes at steps after 60 and before), straight
// and restarted at step 60 (the earlier changes in the checkpoint's history, the later still to
// come): both end bit for bit alike, with all `accepted` changes taken; unsteered, the run ends
// elsewhere.
void expect_steered_restart_identical(const Case& c, const std::string& log_text, int accepted, const std::string& name) {
  const auto log = parse_log(log_text, "test log");
  RunOptions o;
  o.steps = 120;
  SteeringReplay all(log);
  o.steering = &all;
  const RunResult straight = test::run_case(c, test::scratch(name + "-straight"), o);
  EXPECT_EQ(straight.steering_accepted, accepted);
  o.steps = 60;
  SteeringReplay first_half(log);
  o.steering = &first_half;
  const RunResult first = test::run_case(c, test::scratch(name + "-first"), o);
  o.restart = first.last_checkpoint;
  SteeringReplay second_half(log);
  o.steering = &second_half;
  const RunResult second = test::run_case(c, test::scratch(name + "-second"), o);
  ASSERT_EQ(second.final_step, 120) << second.message;
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(straight.last_checkpoint, second.last_checkpoint, &why)) << why;
  o = RunOptions{};
  o.steps = 120;
  const RunResult plain = test::run_case(c, test::scratch(name + "-plain"), o);
  EXPECT_FALSE(test::identical_checkpoints(straight.last_checkpoint, plain.last_checkpoint));
}

// Moving walls under steering: the amplitude and frequency changes of a replayed log live in the
// checkpoint's steering history, so a restart half way continues on the same wall path, bit for bit.
TEST(Restart, SteeredMovingWallsContinueBitIdentically) {
  const Case c = load_case(test::case_path("sloshing_2d.yaml"),
                           {"dp=0.02", "output.interval=0", "probes=[]", "time.dt=2e-4", "tank.motion.ramp=0", "tank.motion.period=0.25",
                            "tank.motion.rotation=3"});
  expect_steered_restart_identical(c, "40 0 motion_amplitude 0 1.8\n70 0 motion_frequency 0 3\n", 2, "moving");
}

// Floating solids steered (docs/live.md): the box of cases/floating_box_2d.yaml on a hinge at its
// bottom with a spring to the tank's top, its hinge's stiffness and the spring's stiffness changed
// at step 40, the hinge's damping at step 70.
TEST(Restart, SteeredFloatingSolidContinuesBitIdentically) {
  if (!body_support()) GTEST_SKIP() << "built without Simbody";
  const Case c = load_case(test::case_path("floating_box_2d.yaml"),
                           {"dp=0.02", "output.interval=0", "probes=[]",
                            "solids=[{name: box, polygon: [[0.9, 0.26], [1.1, 0.26], [1.1, 0.36], [0.9, 0.36]], motion: floating, density: 500, "
                            "centre_of_mass: [1.04, 0.3], hinge: {point: [1.0, 0.26], stiffness: 1}, "
                            "springs: [{point: [1.1, 0.36], anchor: [1.4, 0.5], stiffness: 5}]}]"});
  expect_steered_restart_identical(c, "40 0 hinge_stiffness 0 40\n40 0 spring_stiffness 0 300\n70 0 hinge_damping 0 2\n", 3, "hinge");
}

// A wall moved by a time series named relative to its case file (the lifted gate of
// cases/dam_break_lobovsky_gate.yaml, `file: lobovsky_gate.csv`): the checkpoint, in another
// folder, keeps the series' absolute path in its case, and the restart continues bit for bit.
TEST(Restart, TimeSeriesMotionFromAnotherFolderContinuesBitIdentically) {
  const Case c = load_case(test::case_path("dam_break_lobovsky_gate.yaml"), {"dp=0.02", "output.interval=0", "probes=[]"});
  ASSERT_EQ(c.motions.size(), 1u);
  EXPECT_NE(c.source_yaml.find(std::filesystem::absolute(test::case_path("lobovsky_gate.csv")).lexically_normal().string()),
            std::string::npos)
      << "the effective case names the series by its absolute path";
  RunOptions o;
  o.steps = 80;
  const RunResult straight = test::run_case(c, test::scratch("series-straight"), o);
  o.steps = 40;
  const RunResult first = test::run_case(c, test::scratch("series-first"), o);
  o.restart = first.last_checkpoint;
  const RunResult second = test::run_case(c, test::scratch("series-second"), o);
  ASSERT_EQ(second.final_step, 80) << second.message;
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(straight.last_checkpoint, second.last_checkpoint, &why)) << why;
}

TEST(Threads, OneAndTwoThreadsBitIdentical) {
  // Above the OpenMP grain size (backend/cpu/parallel.hpp) so that two threads really share loops.
  const Case c = load_case(test::case_path("dam_break_column_3d.yaml"),
                           {"dp=0.02", "time.dt=auto", "output.interval=0", "probes=[]"});
  RunOptions o;
  o.steps = 30;
  o.threads = 1;
  const RunResult one = test::run_case(c, test::scratch("threads-1"), o);
  o.threads = 2;
  const RunResult two = test::run_case(c, test::scratch("threads-2"), o);
  ASSERT_GT(one.particles.total(), 20000);
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(one.last_checkpoint, two.last_checkpoint, &why)) << why;
}

TEST(Threads, TheGrainsOfAFreeMachineGiveTheSameBits) {
  // A small 2D case: under the busy machine's grains every loop is serial; under the free
  // machine's (backend/cpu/parallel.hpp, what CoreWatch picks when the cores are this run's) the
  // pair loops and the cheap loops run on two threads. Same bits either way.
  const Case c = load_case(test::case_path("dam_break_buchner_2d.yaml"), {"output.interval=0", "probes=[]"});
  RunOptions o;
  o.steps = 40;
  o.threads = 2;
  cpu::fix_cores_free(false);
  const RunResult busy = test::run_case(c, test::scratch("grain-busy"), o);
  cpu::fix_cores_free(true);
  const RunResult free = test::run_case(c, test::scratch("grain-free"), o);
  cpu::fix_cores_free(std::nullopt);
  ASSERT_GT(free.particles.total(), cpu::kFreeCheapGrain);
  ASSERT_LT(free.particles.total(), cpu::kBusyPairGrain);
  std::string why;
  EXPECT_TRUE(test::identical_checkpoints(busy.last_checkpoint, free.last_checkpoint, &why)) << why;
}

}  // namespace
}  // namespace spate
