// Bitwise reproducibility: restart and thread count must not change a single bit.
#include <gtest/gtest.h>

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

// Checkpoints written before the field registry (format version 1, tests/fixtures/README.md) still
// restart, and continue bit-identically to a straight run of this build.
TEST(Restart, ReadsFormatVersionOneBitIdentically) {
  const std::filesystem::path fixture = std::string(SPATE_SOURCE_DIR) + "/tests/fixtures/checkpoint_v1_tiny_2d_step10.h5";
  ParticleStore p;
  const CheckpointMeta meta = read_checkpoint(fixture, p);
  ASSERT_EQ(meta.format_version, 1);
  ASSERT_EQ(meta.step, 10);
  const Case c = load_case(std::string(SPATE_SOURCE_DIR) + "/tests/cases/tiny_2d.yaml");
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

}  // namespace
}  // namespace spate
