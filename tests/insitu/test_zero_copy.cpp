// Zero copy on the CPU backend, across the process boundary: the pipelines run in the in-situ
// helper process (adaptors/catalyst/insitu_helper.hpp), which maps the solver's particle memory at
// the same address, so the arrays a Catalyst pipeline receives are backed by the solver's own
// buffers. The pipeline (record_arrays.py) reports the addresses of the raw buffers it received
// and every particle's values; this test compares them with what the solver held at that step.
#include <gtest/gtest.h>

#include "../source_dir.hpp"
#include <nlohmann/json.hpp>
#include <unistd.h>
#include <vtkDataArray.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "case/case.hpp"
#include "catalyst_sink.hpp"
#include "particle_dataset.hpp"
#include "particles/particle_memory.hpp"
#include "particles/particle_store.hpp"
#include "sim/simulation.hpp"

namespace fs = std::filesystem;
using namespace spate;

namespace {

struct Particle {
  float x[3], v[3], p, rho;
  int kind, device;
};

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

// The values record_arrays.py saw, by particle id (Python's repr round-trips doubles; floats
// widened to double compare exactly).
std::map<std::uint32_t, Particle> recorded(const fs::path& csv) {
  std::map<std::uint32_t, Particle> seen;
  std::ifstream cf(csv);
  for (std::string line; std::getline(cf, line);) {
    if (line.empty()) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    std::uint32_t id;
    double x[3], v[3], p, rho;
    Particle q{};
    s >> id >> x[0] >> x[1] >> x[2] >> v[0] >> v[1] >> v[2] >> p >> rho >> q.kind >> q.device;
    for (int k = 0; k < 3; ++k) {
      q.x[k] = static_cast<float>(x[k]);
      q.v[k] = static_cast<float>(v[k]);
    }
    q.p = static_cast<float>(p);
    q.rho = static_cast<float>(rho);
    seen[id] = q;
  }
  return seen;
}

// Buffers of one slab, in the order the pipeline reports them: x y z vx vy vz pressure density id kind.
using Buffers = std::array<std::uintptr_t, 10>;

// Wraps the Catalyst sink and keeps, for each in-situ step, the solver's buffers and values that
// the pipeline must have seen.
class CheckingSink : public InSituSink {
 public:
  explicit CheckingSink(catalyst::CatalystSink& inner) : inner_(inner) {}
  bool wants(std::int64_t step, double time) override { return inner_.wants(step, time); }
  std::vector<std::string> failures() const override { return inner_.failures(); }

  void execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) override {
    inner_.execute(step, time, slabs);
    auto& seen = steps[step];
    for (const SlabView& v : slabs) {
      const SlabArray* velocity = v.array("velocity");
      ASSERT_NE(velocity, nullptr);
      const float* pressure = v.array("pressure")->values<float>();
      const float* density = v.array("density")->values<float>();
      const std::uint32_t* ids = v.array("id")->values<std::uint32_t>();
      const std::uint8_t* kind = v.array("kind")->values<std::uint8_t>();
      Buffers b{};
      for (int k = 0; k < 3; ++k) {
        b[k] = address(v.pos[k]);
        b[3 + k] = address(velocity->data[k]);
      }
      b[6] = address(pressure);
      b[7] = address(density);
      b[8] = address(ids);
      b[9] = address(kind);
      buffers[step][v.slab] = b;
      dims = v.dim;
      for (std::size_t i = 0; i < v.owned; ++i) {
        Particle q{};
        for (int k = 0; k < 3; ++k) {
          q.x[k] = v.pos[k] ? v.pos[k][i] : 0.0f;
          q.v[k] = velocity->data[k] ? velocity->values<float>(k)[i] : 0.0f;
        }
        q.p = pressure[i];
        q.rho = density[i];
        q.kind = kind[i];
        q.device = v.slab;
        seen[ids[i]] = q;
      }
    }
  }

  catalyst::CatalystSink& inner_;
  int dims = 3;
  std::map<std::int64_t, std::map<std::uint32_t, Particle>> steps;
  std::map<std::int64_t, std::map<int, Buffers>> buffers;
};

void run_and_check(int devices, const std::string& tag) {
  const fs::path out = fs::path(testing::TempDir()) / ("spate_zero_copy_" + tag);
  fs::remove_all(out);
  fs::create_directories(out / "record");
  setenv("SPATE_RECORD_DIR", (out / "record").c_str(), 1);

  Case c = load_case(test::source_dir() + "/cases/dam_break_2d.yaml", {"output.interval=0", "probes=[]"});
  catalyst::CatalystOptions co;
  co.scripts = {test::source_dir() + "/tests/insitu/record_arrays.py"};
  co.every = 2;
  co.working_dir = out;
  co.helper_program = SPATE_BINARY;
  catalyst::CatalystSink sink(co);  // before the particles exist: their memory is then shared
  ASSERT_TRUE(sink.isolated());
  CheckingSink checking(sink);
  RunOptions o;
  o.out_dir = out;
  o.steps = 4;
  o.devices = devices;
  o.quiet = true;
  o.insitu = &checking;
  const RunResult r = Simulation(c, o).run();
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_TRUE(r.insitu_failures.empty());
  ASSERT_EQ(checking.steps.size(), 3u);  // steps 0, 2, 4
  const SharedParticleMemory* arena = shared_particle_memory();
  ASSERT_NE(arena, nullptr);

  static const char* kNames[] = {"x", "y", "z", "vx", "vy", "vz", "pressure", "density", "id", "kind"};
  for (auto& [step, solver] : checking.steps) {
    // The pipeline, in another process, received arrays over the very buffers the solver holds.
    std::ifstream jf(out / "record" / ("step_" + std::to_string(step) + ".json"));
    ASSERT_TRUE(jf) << "the pipeline did not run at step " << step;
    const auto j = nlohmann::json::parse(jf);
    EXPECT_NE(j["pid"].get<int>(), getpid()) << "the pipeline ran in the solver's process";
    ASSERT_EQ(j["blocks"].size(), static_cast<std::size_t>(devices));
    for (auto& b : j["blocks"]) {
      EXPECT_TRUE(b["soa"].get<bool>()) << "positions or velocities were made interleaved (a copy)";
      const Buffers& want = checking.buffers[step][b["block"].get<int>()];
      for (int k = 0; k < 10; ++k) {
        if ((k % 3 == 2 && k < 6) && checking.dims == 2) continue;  // z: the adaptor's zeros in 2D
        const std::string key = std::string(kNames[k]) + "_buffer";
        EXPECT_EQ(b[key].get<std::uintptr_t>(), want[k]) << key << " at step " << step << " is not the solver's buffer";
        EXPECT_TRUE(arena->contains(reinterpret_cast<const void*>(want[k]))) << key << " is not in the shared arena";
      }
    }
    // And it saw every particle's values exactly.
    const auto seen = recorded(out / "record" / ("step_" + std::to_string(step) + ".csv"));
    EXPECT_EQ(seen.size(), solver.size()) << "step " << step;
    for (auto& [id, got] : seen) {
      ASSERT_TRUE(solver.count(id)) << "unknown particle id " << id;
      const Particle& q = solver.at(id);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(got.x[k], q.x[k]) << "id " << id;
        EXPECT_EQ(got.v[k], q.v[k]) << "id " << id;
      }
      EXPECT_EQ(got.p, q.p);
      EXPECT_EQ(got.rho, q.rho);
      EXPECT_EQ(got.kind, q.kind);
      EXPECT_EQ(got.device, q.device);
    }
  }
}

}  // namespace

// The arena is per process and shared once: CTest runs each test in its own process; run the binary
// with --gtest_filter for one at a time.
TEST(CatalystZeroCopy, PipelineReceivesSolverBuffersOneDevice) { run_and_check(1, "one_device"); }
TEST(CatalystZeroCopy, PipelineReceivesSolverBuffersTwoDevices) { run_and_check(2, "two_devices"); }
// The seam for data that does not come from a running solver (spate post over saved snapshots):
// arrays allocated before the sink existed are on the heap, outside the shared arena; the sink
// copies them into the arena for the step, and the pipeline sees their values exactly.
TEST(CatalystZeroCopy, ArraysOutsideTheArenaAreCopiedForTheHelper) {
  const fs::path out = fs::path(testing::TempDir()) / "spate_zero_copy_staged";
  fs::remove_all(out);
  fs::create_directories(out / "record");
  setenv("SPATE_RECORD_DIR", (out / "record").c_str(), 1);
  ParticleStore p(2);  // before the sink: on the heap
  p.resize(50);
  p.set_owned(50);
  for (std::size_t i = 0; i < 50; ++i) {
    p.pos[0][i] = 0.01f * static_cast<float>(i);
    p.pos[1][i] = 0.5f;
    p.vel[0][i] = static_cast<float>(i);
    p.density[i] = 1000.0f + static_cast<float>(i);
    p.id[i] = static_cast<std::uint32_t>(100 + i);
  }
  catalyst::CatalystOptions co;
  co.scripts = {test::source_dir() + "/tests/insitu/record_arrays.py"};
  co.working_dir = out;
  co.helper_program = SPATE_BINARY;
  catalyst::CatalystSink sink(co);
  ASSERT_FALSE(shared_particle_memory()->contains(p.pos[0].data()));
  sink.execute(7, 0.5, {slab_view(p, 0, 1)});
  EXPECT_TRUE(sink.failures().empty());
  const auto j = nlohmann::json::parse(std::ifstream(out / "record" / "step_7.json"));
  ASSERT_EQ(j["blocks"].size(), 1u);
  EXPECT_NE(j["blocks"][0]["x_buffer"].get<std::uintptr_t>(), address(p.pos[0].data())) << "a heap buffer reached another process";
  const auto seen = recorded(out / "record" / "step_7.csv");
  EXPECT_EQ(seen.size(), 50u);
  for (auto& [id, r] : seen) {
    const std::size_t i = id - 100;
    ASSERT_LT(i, 50u);
    EXPECT_EQ(r.x[0], p.pos[0][i]);
    EXPECT_EQ(r.v[0], p.vel[0][i]);
    EXPECT_EQ(r.rho, p.density[i]);
  }
}

// The dataset's point arrays come from the field registry: a field registered as one FieldSpec
// (here a test-only one) reaches the pipelines as a point array over the solver's own memory.
TEST(ParticleDataset, ARegisteredFieldBecomesAPointArrayOnSolverMemory) {
  static constexpr FieldSpec tracer{"tracer", FieldType::F32, FieldShape::Scalar, FieldRole::State,
                                    kMigrated | kCheckpointed | kGhost | kExported, "tracer", {"tracer"}};
  const FieldExtension registered(tracer);
  ParticleStore p(2);
  p.resize(7);
  p.set_owned(7);
  float* values = nullptr;
  for (const FieldRef& f : p.fields())
    if (f.spec->member == "tracer") values = reinterpret_cast<float*>(f.bytes());
  ASSERT_NE(values, nullptr);
  for (int i = 0; i < 7; ++i) values[i] = 0.5f * static_cast<float>(i) + 3.0f;
  catalyst::ParticleDataset dataset;
  vtkMultiBlockDataSet* data = dataset.update({slab_view(p, 0, 1)});
  auto* block = vtkPolyData::SafeDownCast(data->GetBlock(0));
  ASSERT_NE(block, nullptr);
  vtkDataArray* array = block->GetPointData()->GetArray("tracer");
  ASSERT_NE(array, nullptr) << "the registered field is not a point array";
  EXPECT_EQ(array->GetVoidPointer(0), static_cast<void*>(values)) << "the point array is a copy";
  ASSERT_EQ(array->GetNumberOfTuples(), 7);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(array->GetTuple1(i), values[i]);
  // The built-in exported fields are there too, under their exported names.
  for (const char* name : {"velocity", "density", "pressure", "id", "kind", "device"})
    EXPECT_NE(block->GetPointData()->GetArray(name), nullptr) << name;
}
