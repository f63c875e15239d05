// The steering read path without a Live client: the proxy defined by pipelines/spate_steering.xml
// is created with the run's values, an edit of its properties (what a Live client's state update
// does on the simulation side) is reported once as a SteeringChange, untouched parameters never
// are, and the switches report only being switched on. Then a short run steered through the proxy
// applies the change (insitu_every included) and records it in steering.log.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "case/case.hpp"
#include "catalyst_sink.hpp"
#include "catalyst_steering.hpp"
#include "sim/simulation.hpp"

namespace fs = std::filesystem;
using namespace spate;

namespace {

const fs::path kXml = fs::path(SPATE_SOURCE_DIR) / "pipelines" / "spate_steering.xml";

catalyst::SteeringInitial initial() {
  catalyst::SteeringInitial init;
  init.gravity = {0.0, -9.81, 0.0};
  init.viscosity = 0.001;
  init.artificial_viscosity = 0.02;
  init.insitu_every = 1;
  return init;
}

// Edits the proxy at a chosen step (as a client's edit arriving in that step's CoProcess would).
class EditingSource : public SteeringSource {
 public:
  EditingSource(catalyst::CatalystSteering& inner, std::int64_t at, std::string name, std::vector<double> value)
      : inner_(inner), at_(at), name_(std::move(name)), value_(std::move(value)) {}
  std::vector<SteeringChange> poll(std::int64_t step, double time) override {
    if (step == at_) inner_.set_for_test(name_, value_);
    return inner_.poll(step, time);
  }

 private:
  catalyst::CatalystSteering& inner_;
  std::int64_t at_;
  std::string name_;
  std::vector<double> value_;
};

// Counts in-situ steps (wrapping the real sink so that set_interval reaches it).
class CountingSink : public InSituSink {
 public:
  explicit CountingSink(catalyst::CatalystSink& inner) : inner_(inner) {}
  bool wants(std::int64_t step, double time) override { return inner_.wants(step, time); }
  void execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) override {
    inner_.execute(step, time, slabs);
    steps.push_back(step);
  }
  void set_interval(int every) override { inner_.set_interval(every); }
  std::vector<std::int64_t> steps;

 private:
  catalyst::CatalystSink& inner_;
};

}  // namespace

TEST(SteeringProxy, ReportsOnlyChangesOnce) {
  catalyst::CatalystEngine engine(catalyst::EngineOptions{});  // ParaView's proxy manager, no script
  catalyst::CatalystSteering steering(kXml, initial());
  auto v = steering.values();
  ASSERT_EQ(v.size(), steering_parameters().size());
  EXPECT_EQ(v["gravity"], (std::vector<double>{0.0, -9.81, 0.0}));
  EXPECT_EQ(v["viscosity"], std::vector<double>{0.001});
  EXPECT_TRUE(steering.poll(0, 0.0).empty()) << "the initial values are not changes";

  steering.set_for_test("gravity", {2.0, -9.81, 0.0});
  auto c = steering.poll(3, 0.25);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].name, "gravity");
  EXPECT_EQ(c[0].step, 3);
  EXPECT_EQ(c[0].time, 0.25);
  EXPECT_EQ(c[0].value, (std::vector<double>{2.0, -9.81, 0.0}));
  EXPECT_TRUE(steering.poll(4, 0.3).empty()) << "a change is reported once";

  // Out-of-range values are reported as asked: the solver, not the reader, rejects them.
  steering.set_for_test("viscosity", {50.0});
  c = steering.poll(5, 0.4);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_TRUE(validate(c[0], 2).has_value());

  steering.set_for_test("write_checkpoint", {1});
  c = steering.poll(6, 0.5);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].name, "write_checkpoint");
  steering.set_for_test("write_checkpoint", {0});
  EXPECT_TRUE(steering.poll(7, 0.6).empty()) << "switching off only re-arms";
  steering.set_for_test("write_checkpoint", {1});
  steering.set_for_test("stop", {1});
  c = steering.poll(8, 0.7);
  ASSERT_EQ(c.size(), 2u) << "switched on again: a second request";
  EXPECT_EQ(c[0].name, "write_checkpoint");
  EXPECT_EQ(c[1].name, "stop");
}

TEST(SteeringProxy, SteersARunAndTheInSituInterval) {
  Case c = load_case(fs::path(SPATE_SOURCE_DIR) / "tests" / "cases" / "tiny_2d.yaml", {"output.interval=0", "probes=[]"});
  const fs::path out = fs::temp_directory_path() / "spate_steering_proxy_test";
  fs::remove_all(out);
  catalyst::CatalystOptions co;
  co.scripts = {fs::path(SPATE_SOURCE_DIR) / "pipelines" / "extract.py"};  // any script: the sink must want steps
  co.working_dir = out;
  co.isolation = catalyst::Isolation::kInProcess;  // the steering proxy lives where Catalyst runs
  fs::create_directories(out);
  catalyst::CatalystSink sink(co);
  catalyst::CatalystSteering steering(kXml, initial());
  CountingSink counting(sink);
  EditingSource source(steering, 2, "insitu_every", {3});
  RunOptions o;
  o.out_dir = out;
  o.steps = 9;
  o.quiet = true;
  o.threads = 1;
  o.steering = &source;
  o.insitu = &counting;
  const RunResult r = Simulation(c, o).run();
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.steering_accepted, 1);
  // Every step up to the change at step 2, then every third step.
  EXPECT_EQ(counting.steps, (std::vector<std::int64_t>{0, 1, 2, 3, 6, 9}));
  std::ifstream log(out / "steering.log");
  std::stringstream text;
  text << log.rdbuf();
  EXPECT_NE(text.str().find("2 "), std::string::npos);
  EXPECT_NE(text.str().find(" insitu_every 3"), std::string::npos) << text.str();
  fs::remove_all(out);
}
