// The worker's side of the backend interface (StepKernels), checked on the CPU: a stand-in backend
// keeps its own copy of the particles, like a GPU does, and runs the CPU loops on that copy. If the
// worker forgot to publish or fetch anything, the stand-in would compute from stale data and the
// run would differ from the plain CPU backend. The CUDA backend follows the same protocol; its own
// test (CudaBackend.*) needs a GPU and skips without one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <memory>
#include <numeric>
#include <thread>

#include "backend/cpu/cpu_backend.hpp"
#include "backend/cuda/device_runtime.hpp"
#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "sim/slab_worker.hpp"

namespace spate {
namespace {

// A backend whose particles live in a separate store (the "device"); the host store is stale
// except where the protocol says it must be brought up to date.
class MirrorKernels final : public StepKernels {
 public:
  const char* name() const override { return "mirror"; }
  void predict(ParticleStore&, const PhysicsParams& P, float dt) override { cpu::predict(dev_, P, dt); }
  void correct(ParticleStore&, const PhysicsParams& P, float dt) override { cpu::correct(dev_, P, dt); }
  void equation_of_state(ParticleStore&, const PhysicsParams& P) override { cpu::equation_of_state(dev_, P); }
  void summation_density(ParticleStore&, const CellGrid& g, const PhysicsParams& P) override {
    cpu::summation_density(dev_, g, P);
  }
  void wall_state(ParticleStore&, const CellGrid& g, const PhysicsParams& P) override { cpu::wall_state(dev_, g, P); }
  void fluid_rates(ParticleStore&, const CellGrid& g, const PhysicsParams& P) override { cpu::fluid_rates(dev_, g, P); }
  float min_time_step(const ParticleStore&, const PhysicsParams& P, const TimeStepControl& c) override {
    return cpu::min_time_step(dev_, P, c);
  }
  void publish(const ParticleStore& host, const CellGrid&) override {
    dev_ = host;
    ++publishes;
  }
  void publish_fields(const ParticleStore& host, FieldSet set, std::size_t first, std::size_t last) override {
    copy(const_cast<ParticleStore&>(host), dev_, set, first, last);
  }
  void fetch(ParticleStore& host, FieldSet set, std::size_t first, std::size_t last) override {
    copy(dev_, host, set, first, last);
  }
  int publishes = 0;

 private:
  static void copy(ParticleStore& from, ParticleStore& to, FieldSet set, std::size_t first, std::size_t last) {
    auto a = from.fields(), b = to.fields();
    for (std::size_t f = 0; f < a.size(); ++f)
      if (in_set(a[f], set) && last > first)
        std::memcpy(b[f].bytes() + first * b[f].elem_size, a[f].bytes() + first * a[f].elem_size, (last - first) * a[f].elem_size);
  }
  ParticleStore dev_;
};

// Every checkpoint field of every particle, ordered by id, after `steps` fixed steps on `slabs`
// in-process slabs, each with the kernels `make` gives it.
std::vector<std::vector<char>> run(const Case& c, int slabs, int steps, const std::function<std::unique_ptr<StepKernels>()>& make,
                                   std::vector<float>* dts = nullptr) {
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  const ParticleStore initial = generate_particles(c);
  InProcessHub hub(slabs);
  std::vector<ParticleStore> finals(slabs);
  std::vector<std::vector<float>> step_sizes(slabs);
  auto body = [&](int s) {
    auto t = hub.endpoint(s, L.periodic[0]);
    SlabWorker w(L, P, *t);
    if (make) w.use_kernels(make());
    w.take_share(initial, SlabLayout::uniform(L.cells[0], slabs));
    w.prepare(true);
    for (int k = 0; k < steps; ++k) {
      const float dt = static_cast<float>(t->min(w.local_time_step(TimeStepControl{})));
      step_sizes[s].push_back(dt);
      if (w.step(dt)) {  // a fault is collective: every slab stops here
        ADD_FAILURE() << "unstable at step " << k;
        break;
      }
    }
    finals[s] = w.particles();
    finals[s].resize(finals[s].owned());
  };
  std::vector<std::thread> pool;
  for (int s = 0; s < slabs; ++s) pool.emplace_back(body, s);
  for (auto& th : pool) th.join();
  if (dts) *dts = step_sizes[0];
  ParticleStore all(c.dim);
  for (auto& f : finals)
    for (std::size_t i = 0; i < f.size(); ++i) all.append_from(f, i);
  std::vector<std::uint32_t> order(all.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return all.id[a] < all.id[b]; });
  all.permute(0, order);
  std::vector<std::vector<char>> out;
  for (auto& f : all.fields())
    if (f.checkpoint) out.emplace_back(f.bytes(), f.bytes() + all.size() * f.elem_size);
  return out;
}

Case small_dam_break() {
  // The 2D dam break, shortened so that a few steps take milliseconds.
  return load_case(std::string(SPATE_SOURCE_DIR) + "/cases/dam_break_2d.yaml", {"tank.size=[0.16, 0.12]"});
}

}  // namespace

TEST(StepKernels, ASeparateCopyOfTheParticlesGivesBitIdenticalResults) {
  const Case c = small_dam_break();
  std::vector<float> dt_cpu, dt_mirror;
  // Three slabs put a face inside the water column, so ghosts carry fluid and loaded walls.
  const auto cpu = run(c, 3, 12, nullptr, &dt_cpu);
  const auto mirror = run(c, 3, 12, [] { return std::make_unique<MirrorKernels>(); }, &dt_mirror);
  EXPECT_EQ(dt_cpu, dt_mirror);
  ASSERT_EQ(cpu.size(), mirror.size());
  for (std::size_t f = 0; f < cpu.size(); ++f) EXPECT_TRUE(cpu[f] == mirror[f]) << "checkpoint field " << f;
}

TEST(StepKernels, SplitDoesNotChangeTheResultThroughTheInterface) {
  const Case c = small_dam_break();
  auto mirror = [] { return std::make_unique<MirrorKernels>(); };
  const auto one = run(c, 1, 10, mirror), three = run(c, 3, 10, mirror);
  ASSERT_EQ(one.size(), three.size());
  for (std::size_t f = 0; f < one.size(); ++f) EXPECT_TRUE(one[f] == three[f]) << "checkpoint field " << f;
}

TEST(StepKernels, SummationDensityRefreshesGhostsThroughTheInterface) {
  const Case c = load_case(std::string(SPATE_SOURCE_DIR) + "/cases/dam_break_2d.yaml",
                           {"tank.size=[0.16, 0.12]", "density.mode=summation"});
  const auto cpu = run(c, 3, 6, nullptr);
  const auto mirror = run(c, 3, 6, [] { return std::make_unique<MirrorKernels>(); });
  for (std::size_t f = 0; f < cpu.size(); ++f) EXPECT_TRUE(cpu[f] == mirror[f]) << "checkpoint field " << f;
}

// The real thing: the CUDA kernels against the CPU loops. Skips, visibly, on machines without a GPU
// (the CI machine has none; see docs/gpu.md for what is therefore untested).
TEST(CudaBackend, MatchesTheCpuBackendOnTheDamBreak) {
  if (gpu::device_count() == 0) GTEST_SKIP() << "no CUDA device (" << (gpu::built_with_cuda() ? "built with CUDA" : "built without CUDA") << ")";
  const Case c = small_dam_break();
  std::vector<float> dt_cpu, dt_gpu;
  const auto cpu = run(c, 3, 12, nullptr, &dt_cpu);
  int next = 0;
  const auto gpu = run(c, 3, 12, [&] { return gpu::make_cuda_kernels(next++ % gpu::device_count(), c.dim); }, &dt_gpu);
  // Same sums in the same order, no FMA (--fmad=false); only powf (tait_density) may round differently.
  ASSERT_EQ(dt_cpu.size(), dt_gpu.size());
  for (std::size_t k = 0; k < dt_cpu.size(); ++k) EXPECT_NEAR(dt_cpu[k], dt_gpu[k], 1e-6f * dt_cpu[k]);
  ASSERT_EQ(cpu.size(), gpu.size());
  for (std::size_t f = 0; f < cpu.size(); ++f) ASSERT_EQ(cpu[f].size(), gpu[f].size());
  // Positions (field 0 = x, 1 = y) agree to far below a particle spacing.
  for (int axis = 0; axis < 2; ++axis) {
    const auto* a = reinterpret_cast<const float*>(cpu[axis].data());
    const auto* b = reinterpret_cast<const float*>(gpu[axis].data());
    for (std::size_t i = 0; i < cpu[axis].size() / sizeof(float); ++i) EXPECT_NEAR(a[i], b[i], 1e-4f * c.dp);
  }
}

TEST(CudaBackend, ThreeSlabsGiveTheSameAnswerAsOneOnTheGpu) {
  if (gpu::device_count() == 0) GTEST_SKIP() << "no CUDA device";
  const Case c = small_dam_break();
  auto make = [&] { return gpu::make_cuda_kernels(0, c.dim); };
  const auto one = run(c, 1, 10, make), three = run(c, 3, 10, make);
  for (std::size_t f = 0; f < one.size(); ++f) EXPECT_TRUE(one[f] == three[f]) << "checkpoint field " << f;
}

}  // namespace spate
