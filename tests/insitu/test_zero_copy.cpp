// Zero copy on the CPU backend: the arrays a Catalyst pipeline receives are the solver's own
// buffers, and the pipeline sees every particle's values exactly. The pipeline (record_arrays.py)
// reports the addresses of the array objects and raw buffers it received and every particle's
// values; this test compares them with what the solver held at that step.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <vtkMultiBlockDataSet.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSOADataArrayTemplate.h>

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

// Wraps the Catalyst sink; after each in-situ step checks the dataset against the solver's views
// and keeps what the pipeline must have seen.
class CheckingSink : public InSituSink {
 public:
  explicit CheckingSink(catalyst::CatalystSink& inner) : inner_(inner) {}
  bool wants(std::int64_t step, double time) override { return inner_.wants(step, time); }
  std::vector<std::string> failures() const override { return inner_.failures(); }

  void execute(std::int64_t step, double time, const std::vector<SlabView>& slabs) override {
    inner_.execute(step, time, slabs);
    vtkMultiBlockDataSet* data = inner_.last_dataset();
    auto& seen = steps[step];
    for (const SlabView& v : slabs) {
      auto* block = vtkPolyData::SafeDownCast(data->GetBlock(v.slab));
      ASSERT_NE(block, nullptr);
      ASSERT_EQ(block->GetNumberOfPoints(), static_cast<vtkIdType>(v.owned));
      auto* xyz = vtkSOADataArrayTemplate<float>::SafeDownCast(block->GetPoints()->GetData());
      auto* vel = vtkSOADataArrayTemplate<float>::SafeDownCast(block->GetPointData()->GetArray("velocity"));
      ASSERT_NE(xyz, nullptr);
      ASSERT_NE(vel, nullptr);
      const SlabArray* velocity = v.array("velocity");
      ASSERT_NE(velocity, nullptr);
      for (int k = 0; k < v.dim; ++k) {
        EXPECT_EQ(xyz->GetComponentArrayPointer(k), v.pos[k]) << "position component " << k << " is a copy";
        EXPECT_EQ(vel->GetComponentArrayPointer(k), velocity->values<float>(k)) << "velocity component " << k << " is a copy";
      }
      auto buffer = [&](const char* name) { return address(block->GetPointData()->GetArray(name)->GetVoidPointer(0)); };
      auto solver = [&](const char* name) { return address(v.array(name)->data[0]); };
      for (const char* name : {"pressure", "density", "id", "kind"}) EXPECT_EQ(buffer(name), solver(name)) << name << " is a copy";
      objects[step][v.slab] = {address(xyz), address(vel), buffer("pressure"), buffer("density"), buffer("id"), buffer("kind")};
      const float* pressure = v.array("pressure")->values<float>();
      const float* density = v.array("density")->values<float>();
      const std::uint8_t* kind = v.array("kind")->values<std::uint8_t>();
      const std::uint32_t* ids = v.array("id")->values<std::uint32_t>();
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
  std::map<std::int64_t, std::map<std::uint32_t, Particle>> steps;
  std::map<std::int64_t, std::map<int, std::array<std::uintptr_t, 6>>> objects;
};

void run_and_check(int devices, const std::string& tag) {
  const fs::path out = fs::path(testing::TempDir()) / ("spate_zero_copy_" + tag);
  fs::remove_all(out);
  fs::create_directories(out / "record");
  setenv("SPATE_RECORD_DIR", (out / "record").c_str(), 1);

  Case c = load_case(SPATE_SOURCE_DIR "/cases/dam_break_2d.yaml", {"output.interval=0", "probes=[]"});
  catalyst::CatalystOptions co;
  co.scripts = {SPATE_SOURCE_DIR "/tests/insitu/record_arrays.py"};
  co.every = 2;
  co.working_dir = out;
  catalyst::CatalystSink sink(co);
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

  for (auto& [step, solver] : checking.steps) {
    // The pipeline received the very array objects and buffers the adaptor built on solver memory.
    std::ifstream jf(out / "record" / ("step_" + std::to_string(step) + ".json"));
    ASSERT_TRUE(jf) << "the pipeline did not run at step " << step;
    const auto j = nlohmann::json::parse(jf);
    ASSERT_EQ(j["blocks"].size(), static_cast<std::size_t>(devices));
    for (auto& b : j["blocks"]) {
      const auto& want = checking.objects[step][b["block"].get<int>()];
      EXPECT_EQ(b["points_object"].get<std::uintptr_t>(), want[0]);
      EXPECT_EQ(b["velocity_object"].get<std::uintptr_t>(), want[1]);
      EXPECT_EQ(b["pressure_buffer"].get<std::uintptr_t>(), want[2]);
      EXPECT_EQ(b["density_buffer"].get<std::uintptr_t>(), want[3]);
      EXPECT_EQ(b["id_buffer"].get<std::uintptr_t>(), want[4]);
      EXPECT_EQ(b["kind_buffer"].get<std::uintptr_t>(), want[5]);
    }
    // And it saw every particle's values exactly (Python's repr round-trips doubles; floats
    // widened to double compare exactly).
    std::ifstream cf(out / "record" / ("step_" + std::to_string(step) + ".csv"));
    std::size_t rows = 0;
    for (std::string line; std::getline(cf, line);) {
      if (line.empty()) continue;
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream s(line);
      std::uint32_t id;
      double x[3], v[3], p, rho;
      int kind, device;
      s >> id >> x[0] >> x[1] >> x[2] >> v[0] >> v[1] >> v[2] >> p >> rho >> kind >> device;
      ASSERT_TRUE(solver.count(id)) << "unknown particle id " << id;
      const Particle& q = solver.at(id);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(static_cast<float>(x[k]), q.x[k]) << "id " << id;
        EXPECT_EQ(static_cast<float>(v[k]), q.v[k]) << "id " << id;
      }
      EXPECT_EQ(static_cast<float>(p), q.p);
      EXPECT_EQ(static_cast<float>(rho), q.rho);
      EXPECT_EQ(kind, q.kind);
      EXPECT_EQ(device, q.device);
      ++rows;
    }
    EXPECT_EQ(rows, solver.size()) << "step " << step;
  }
}

}  // namespace

// One Catalyst session per process (ParaView finalises MPI when it ends): CTest runs each test in
// its own process; run the binary with --gtest_filter for one at a time.
TEST(CatalystZeroCopy, PipelineReceivesSolverBuffersOneDevice) { run_and_check(1, "one_device"); }
TEST(CatalystZeroCopy, PipelineReceivesSolverBuffersTwoDevices) { run_and_check(2, "two_devices"); }

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
