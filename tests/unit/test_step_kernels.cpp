// The worker's side of the backend interface (StepKernels), checked on the CPU: a stand-in backend
// keeps its own copy of the particles, like a GPU does, and runs the CPU loops on that copy. If the
// worker forgot to publish or fetch anything, the stand-in would compute from stale data and the
// run would differ from the plain CPU backend. The CUDA backend follows the same protocol; its own
// test (CudaBackend.*) needs a GPU and skips without one.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <functional>
#include <memory>
#include <numeric>
#include <thread>
#include <utility>

#include "backend/cpu/cpu_backend.hpp"
#include "backend/cuda/device_runtime.hpp"
#include "case/case.hpp"
#include "case/generator.hpp"
#include "comm/in_process_transport.hpp"
#include "domain/host_slab_arrays.hpp"
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
  void fluid_rates_cells(ParticleStore&, const CellGrid& g, const PhysicsParams& P, std::uint32_t first_cell,
                         std::uint32_t last_cell) override {
    cpu::fluid_rates(dev_, g, P, first_cell, last_cell);
  }
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

// The device-resident protocol on the CPU: the particles live in HostSlabArrays (the host twin of
// the CUDA backend's arrays), the worker runs SlabTopology on them (migration, sort, halo, refresh
// with the interior/boundary overlap) and the physics are the CPU loops. The host store is only a
// mirror, filled when the worker's particles() are read.
class ResidentKernels : public StepKernels {
 public:
  explicit ResidentKernels(int dim, bool poison = false) : arrays_(dim, poison) {}
  const char* name() const override { return "resident"; }
  void predict(ParticleStore&, const PhysicsParams& P, float dt) override { cpu::predict(store(), P, dt); }
  void correct(ParticleStore&, const PhysicsParams& P, float dt) override { cpu::correct(store(), P, dt); }
  void equation_of_state(ParticleStore&, const PhysicsParams& P) override { cpu::equation_of_state(store(), P); }
  void summation_density(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    cpu::summation_density(store(), arrays_.grid(), P);
  }
  void wall_state(ParticleStore&, const CellGrid&, const PhysicsParams& P) override { cpu::wall_state(store(), arrays_.grid(), P); }
  // The CPU loop computes every owned particle; only [range) keeps its new rates, so a particle
  // computed in the interior pass (before the halo arrived) keeps what it got from stale ghosts.
  void fluid_rates_range(const CellGrid&, const PhysicsParams& P, ParticleRange range) override {
    ParticleStore& p = store();
    ParticleStore before = p;
    cpu::fluid_rates(p, arrays_.grid(), P);
    auto keep = [&](FieldVector<float>& now, const FieldVector<float>& old) {
      for (std::size_t i = 0; i < p.owned(); ++i)
        if (i < range.first || i >= range.end()) now[i] = old[i];
    };
    for (int k = 0; k < p.dim(); ++k) keep(p.acc[k], before.acc[k]);
    keep(p.density_rate, before.density_rate);
    ++ranges;
  }
  float min_time_step(const ParticleStore&, const PhysicsParams& P, const TimeStepControl& c) override {
    return cpu::min_time_step(store(), P, c);
  }
  SlabArrays* resident() override { return &arrays_; }
  ParticleStore& device_store() { return arrays_.store(); }
  int ranges = 0;

 private:
  // Poisons the Refresh fields of the halo ghosts and of their images as soon as a refresh is
  // staged: whatever the interior pass reads of them is NaN, which then shows in the results.
  class PoisoningArrays final : public HostSlabArrays {
   public:
    PoisoningArrays(int dim, bool poison) : HostSlabArrays(dim), poison_(poison) {}
    void stage(Side side, FieldSet set, ParticleRange range, Shift shift) override {
      HostSlabArrays::stage(side, set, range, shift);
      if (!poison_ || set != FieldSet::Refresh) return;
      for (auto& f : store().fields()) {
        if (!in_set(f, FieldSet::Refresh)) continue;
        float* v = reinterpret_cast<float*>(f.bytes());
        for (Side s : {kLeft, kRight})
          for (std::uint32_t slot : halo_slots(s)) v[slot] = NAN;
        for (int axis = 1; axis < 3; ++axis)
          for (std::uint32_t slot : image_targets(axis, ImagePart::Halo)) v[slot] = NAN;
      }
    }

   private:
    bool poison_;
  };
  ParticleStore& store() { return arrays_.store(); }
  PoisoningArrays arrays_;
};

// The CPU backend's loops on the host store, except that the halo ghosts (and their periodic
// images: every ghost outside the owned x columns) get NaN in their Refresh fields when a refresh
// starts, until the first fluid pass after it is done. That first pass is the interior one: if it
// read a halo ghost, NaN would reach the results. The halo then overwrites the poison.
class PoisonedInteriorKernels final : public StepKernels {
 public:
  explicit PoisonedInteriorKernels(bool every_pass = false) : every_pass_(every_pass) {}
  const char* name() const override { return "poisoned interior"; }
  void predict(ParticleStore& p, const PhysicsParams& P, float dt) override { cpu::predict(p, P, dt); }
  void correct(ParticleStore& p, const PhysicsParams& P, float dt) override { cpu::correct(p, P, dt); }
  void equation_of_state(ParticleStore& p, const PhysicsParams& P) override { cpu::equation_of_state(p, P); }
  void summation_density(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) override { cpu::summation_density(p, g, P); }
  void wall_state(ParticleStore& p, const CellGrid& g, const PhysicsParams& P) override { cpu::wall_state(p, g, P); }
  void fluid_rates_cells(ParticleStore& p, const CellGrid& g, const PhysicsParams& P, std::uint32_t first_cell,
                         std::uint32_t last_cell) override {
    if (std::exchange(armed_, every_pass_)) {
      for (auto& f : p.fields()) {
        if (!in_set(f, FieldSet::Refresh)) continue;
        float* v = reinterpret_cast<float*>(f.bytes());
        for (std::size_t i = p.owned(); i < p.size(); ++i)
          if (!g.owns_column(g.lattice().cell_of(p.pos[0][i], 0))) v[i] = NAN;
      }
    }
    cpu::fluid_rates(p, g, P, first_cell, last_cell);
  }
  float min_time_step(const ParticleStore& p, const PhysicsParams& P, const TimeStepControl& c) override {
    return cpu::min_time_step(p, P, c);
  }
  // The worker asks for the owners' Refresh fields right before it stages a refresh.
  void fetch(ParticleStore&, FieldSet set, std::size_t, std::size_t) override { armed_ = armed_ || set == FieldSet::Refresh; }

 private:
  bool every_pass_;
  bool armed_ = false;
};

// Every checkpoint field of every particle, ordered by id, after `steps` fixed steps on `slabs`
// in-process slabs, each with the kernels `make` gives it.
std::vector<std::vector<char>> run(const Case& c, int slabs, int steps, const std::function<std::unique_ptr<StepKernels>()>& make,
                                   std::vector<float>* dts = nullptr, int balance_every = 0, std::atomic<bool>* faulted = nullptr) {
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
      if (balance_every > 0 && k > 0 && k % balance_every == 0) w.rebalance(2);
      const float dt = static_cast<float>(t->min(w.local_time_step(TimeStepControl{})));
      step_sizes[s].push_back(dt);
      if (w.step(dt)) {  // a fault is collective: every slab stops here
        if (faulted) *faulted = true;
        else ADD_FAILURE() << "unstable at step " << k;
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
    if (f.has(kCheckpointed)) out.emplace_back(f.bytes(), f.bytes() + all.size() * f.elem_size);
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

// The device orchestration (SlabTopology over SlabArrays, the resident worker path) against the
// CPU backend, on the host twin of the device arrays: every checkpoint field bit for bit.
void expect_same(const std::vector<std::vector<char>>& a, const std::vector<std::vector<char>>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t f = 0; f < a.size(); ++f) EXPECT_TRUE(a[f] == b[f]) << "checkpoint field " << f;
}

TEST(HostPath, TheInteriorFluidPassNeedsNoHaloGhost) {
  // The CPU backend computes the interior columns' fluid rates before it waits for the halo
  // refresh. With the halo ghosts poisoned during that pass the results must still be the plain
  // CPU backend's: on the dam break (faces in the water) and with periodic y (images of owned
  // columns are refreshed before the interior pass, images of halo ghosts after it).
  const Case dam = small_dam_break();
  expect_same(run(dam, 3, 8, nullptr), run(dam, 3, 8, [] { return std::make_unique<PoisonedInteriorKernels>(); }));
  const Case periodic = load_case(std::string(SPATE_SOURCE_DIR) + "/cases/hydrostatic_3d.yaml",
                                  {"tank.size=[0.3, 0.2, 0.3]", "fluid_blocks=[{min: [0, 0, 0], max: [0.3, 0.2, 0.1]}]",
                                   "tank.periodic=[y]"});
  expect_same(run(periodic, 3, 4, nullptr), run(periodic, 3, 4, [] { return std::make_unique<PoisonedInteriorKernels>(); }));
  // The poison is effective: poisoned again before the boundary passes, which do read the halo,
  // it makes the first step fail the health check.
  std::atomic<bool> faulted = false;
  run(dam, 3, 8, [] { return std::make_unique<PoisonedInteriorKernels>(true); }, nullptr, 0, &faulted);
  EXPECT_TRUE(faulted);
}

TEST(ResidentTopology, ReproducesTheCpuBackendOnOneTwoAndThreeSlabs) {
  const Case c = small_dam_break();
  for (int slabs : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs");
    std::vector<float> dt_cpu, dt_res;
    const auto cpu = run(c, slabs, 12, nullptr, &dt_cpu);
    const auto res = run(c, slabs, 12, [&] { return std::make_unique<ResidentKernels>(c.dim, true); }, &dt_res);
    EXPECT_EQ(dt_cpu, dt_res);
    expect_same(cpu, res);
  }
}

TEST(ResidentTopology, SummationDensityAndPeriodicXMatchTheCpuBackend) {
  const Case summation = load_case(std::string(SPATE_SOURCE_DIR) + "/cases/dam_break_2d.yaml",
                                   {"tank.size=[0.16, 0.12]", "density.mode=summation"});
  expect_same(run(summation, 3, 6, nullptr), run(summation, 3, 6, [&] { return std::make_unique<ResidentKernels>(2, true); }));
  // Periodic x: halo copies wrap with the period; one slab is its own neighbour.
  const Case channel = load_case(std::string(SPATE_SOURCE_DIR) + "/cases/poiseuille_2d.yaml", {});
  for (int slabs : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs, periodic x");
    expect_same(run(channel, slabs, 6, nullptr), run(channel, slabs, 6, [&] { return std::make_unique<ResidentKernels>(2, true); }));
  }
}

TEST(ResidentTopology, PeriodicImagesIn3dMatchTheCpuBackend) {
  // Periodic y makes images of owned particles (refreshed before the interior pass) and of halo
  // ghosts (poisoned until the halo arrives).
  const Case c = load_case(std::string(SPATE_SOURCE_DIR) + "/cases/hydrostatic_3d.yaml",
                           {"tank.size=[0.3, 0.2, 0.3]", "fluid_blocks=[{min: [0, 0, 0], max: [0.3, 0.2, 0.1]}]", "tank.periodic=[y]"});
  for (int slabs : {1, 3}) {
    SCOPED_TRACE(std::to_string(slabs) + " slabs");
    expect_same(run(c, slabs, 4, nullptr), run(c, slabs, 4, [&] { return std::make_unique<ResidentKernels>(3, true); }));
  }
}

TEST(ResidentTopology, MovingFacesHandParticlesOverLikeTheCpuBackend) {
  const Case c = small_dam_break();
  auto resident = [&] { return std::make_unique<ResidentKernels>(c.dim); };
  expect_same(run(c, 3, 12, nullptr, nullptr, 3), run(c, 3, 12, resident, nullptr, 3));
}

TEST(ResidentTopology, TheInteriorPassIsUsedAndNeedsNoGhost) {
  // With poisoned ghosts a wrong interior (one that reads a ghost) gives NaN rates: the CPU
  // comparison above would fail. Here: the interior pass exists on slabs at least three columns wide.
  const Case c = small_dam_break();
  const Lattice L = make_lattice(c);
  ASSERT_GE(L.cells[0], 9);
  CellGrid grid;
  grid.configure(L, 0, L.cells[0]);
  std::vector<std::uint32_t> starts(L.cells[0] + 1);
  for (int k = 0; k <= L.cells[0]; ++k) starts[k] = 10u * k;
  const OwnedSplit s = plan_owned_split(grid, starts);
  EXPECT_EQ(s.before, (ParticleRange{0, 10}));
  EXPECT_EQ(s.interior, (ParticleRange{10, 10u * (L.cells[0] - 2)}));
  EXPECT_EQ(s.after.end(), 10u * L.cells[0]);
}

TEST(ResidentTopology, DeviceHealthAndDomainChecksFindTheHostsFault) {
  const Case c = small_dam_break();
  const Lattice L = make_lattice(c);
  const PhysicsParams P = physics_params(c);
  const ParticleStore initial = generate_particles(c);
  InProcessHub hub(1);
  auto t = hub.endpoint(0, L.periodic[0]);
  SlabWorker host(L, P, *t), dev(L, P, *t);
  auto kernels = std::make_unique<ResidentKernels>(c.dim);
  ParticleStore& device = kernels->device_store();
  dev.use_kernels(std::move(kernels));
  for (SlabWorker* w : {&host, &dev}) {
    w->take_share(initial, SlabLayout::uniform(L.cells[0], 1));
    w->prepare(true);
  }
  // Every fluid particle fails a density window below rho0: the lowest fluid id, same message.
  const auto a = host.health(0.5f, 0.9f), b = dev.health(0.5f, 0.9f);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->id, b->id);
  EXPECT_EQ(a->what, b->what);
  EXPECT_FALSE(dev.health(0.5f, 2.0f));
  // Two fluid particles thrown out of the domain: the step stops at the lower id, host's message.
  auto throw_out = [](ParticleStore& p, std::uint32_t id, float v) {
    for (std::size_t i = 0; i < p.owned(); ++i)
      if (p.id[i] == id) p.vel[0][i] = v;
  };
  std::vector<std::uint32_t> fluid;
  for (std::size_t i = 0; i < device.owned(); ++i)
    if (is_fluid(device.material[i])) fluid.push_back(device.id[i]);
  ASSERT_GE(fluid.size(), 2u);
  std::sort(fluid.begin(), fluid.end());
  for (ParticleStore* p : {&host.particles(), &device}) {
    throw_out(*p, fluid[fluid.size() / 2], 1e6f);
    throw_out(*p, fluid.back(), -1e6f);
  }
  const auto fa = host.step(1e-3f), fb = dev.step(1e-3f);
  ASSERT_TRUE(fa && fb);
  EXPECT_EQ(fa->id, fluid[fluid.size() / 2]);
  EXPECT_EQ(fa->id, fb->id);
  EXPECT_EQ(fa->what, fb->what);
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
