// The CUDA driver: the same physics bodies as backend/cpu (solver/physics, SPATE_HD), one thread per
// particle, each summing its neighbours sequentially in the (cell, id) order of CellGridView, so
// there are no atomics and every sum is accumulated in the same order whatever the split into
// slabs; the fluid pass, most of a step, runs a half-warp per particle in the CPU's lane order
// (pair_lanes.hpp), which gives the CPU's bits. The particles stay on the device (DeviceSlabArrays, device_arrays.cu); the worker runs
// the topology on them through the SlabArrays primitives (domain/slab_topology.cpp).
#include <cuda_runtime.h>

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "../../physics/dispatch.hpp"
#include "../../physics/eos.hpp"
#include "../../physics/fluid_interactions.hpp"
#include "../../physics/integrator.hpp"
#include "../../physics/wall_boundary.hpp"
#include "../pair_lanes.hpp"
#include "../particle_updates.hpp"
#include "device_arrays.cuh"
#include "device_plan.hpp"
#include "device_runtime.hpp"

namespace spate::gpu {

namespace {

// Global cell coordinates of particle i: the cell its (unchanged since the sort) position is in,
// which is the owned cell whose coordinates the CPU loop passes.
template <int Dim>
__device__ void cell_coords(const Lattice& L, const DeviceFields& d, std::uint32_t i, int g[3]) {
  g[0] = g[1] = g[2] = 0;
  for (int a = 0; a < Dim; ++a) g[a] = L.cell_of(d.pos[a][i], a);
}

__device__ std::uint32_t thread_index() { return blockIdx.x * blockDim.x + threadIdx.x; }

__global__ void predict_kernel(DeviceFields d, std::uint32_t n, float dt, PhysicsParams P) {
  const std::uint32_t i = thread_index();
  if (i < n) predict_particle(P, d, i, dt);
}

__global__ void correct_kernel(DeviceFields d, int dim, std::uint32_t n, float dt, bool continuity, PhysicsParams P) {
  const std::uint32_t i = thread_index();
  if (i >= n) return;
  if (P.heat.on) correct_temperature(P, d, i, dt);
  if (!P.is_fluid(d.material[i])) return;
  for (int k = 0; k < dim; ++k) correct(d.vel[k][i], d.acc[k][i], d.acc_prev[k][i], dt);
  if (continuity) correct_density(d.density[i], d.density_rate[i], d.density_rate_prev[i], dt, density_floor(P, d.material[i]));
  if (P.shifting.enabled)
    for (int k = 0; k < dim; ++k) apply_shift(d.pos[k][i], d.shift[k][i]);
  if (P.shifting.enabled && P.shifting.correct_velocity)
    for (int k = 0; k < dim; ++k) d.vel[k][i] += d.shift_velocity[k][i];
}

__global__ void eos_kernel(DeviceFields d, std::uint32_t n, PhysicsParams P) {
  const std::uint32_t i = thread_index();
  if (i < n && P.is_fluid(d.material[i])) d.pressure[i] = fluid_pressure(P, P.materials.of(d.material[i]), d.density[i]);
}

// One thread per owned particle running one of the shared per-particle bodies
// (backend/particle_updates.hpp), named by a tag so that the neighbour loops share one kernel.
struct SummationDensityPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_summation_density<Kernel, Dim>(P, v, d, i, g);
  }
};
struct WallStatePass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_wall_state<Kernel, Dim>(P, v, d, i, g);
  }
};
struct ShiftingPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3], float dt) {
    update_shift<Kernel, Dim>(P, v, d, i, g, dt);
  }
};
struct ShiftDensityPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_shift_density<Kernel, Dim>(P, v, d, i, g);
  }
};
template <bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>
struct FluidRatesPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_fluid_rates<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(P, v, d, i, g);
  }
};

struct ColourGradientPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_colour_gradient<Kernel, Dim>(P, v, d, i, g);
  }
};
struct DensityGradientPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_density_gradient<Kernel, Dim>(P, v, d, i, g);
  }
};
struct AntuonoDiffusionPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    add_antuono_diffusion<Kernel, Dim>(P, v, d, i, g);
  }
};
struct SpsStressPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_sps_stress<Kernel, Dim>(P, v, d, i, g);
  }
};
struct SpsAccelerationPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    add_sps_acceleration<Kernel, Dim>(P, v, d, i, g);
  }
};
struct WallTemperaturePass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_wall_temperature<Kernel, Dim>(P, v, d, i, g);
  }
};
// `fused`: the fluid particles' conduction was summed by the half-warp fluid pass (fused_heat).
struct HeatRatesPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3], bool fused) {
    if (fused && P.is_fluid(d.material[i])) return;
    update_heat_rates<Kernel, Dim>(P, v, d, i, g);
  }
};
struct SurfaceTensionPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    add_surface_tension<Kernel, Dim>(P, v, d, i, g);
  }
};

// The fluid pass's team (pair_lanes.hpp): the 16 threads of a half-warp share one fluid particle,
// one lane each. A ballot tests 16 candidates at once; the in-support ones are dealt to the lanes
// in order and run together once every lane holds one, so the pair terms run on full lanes; the
// lanes' partial sums are added in lane order through shuffles.
struct HalfWarp {
  static constexpr int kHeld = 1;
  int lane;          // threadIdx.x mod 16
  unsigned members;  // the half-warp's threads in the warp's masks
  unsigned shift;    // 0 or 16: where they sit in a ballot
  __device__ bool leader() const { return lane == 0; }
  template <class Predicate>
  __device__ unsigned ballot(Predicate&& inside) const {
    return (__ballot_sync(members, inside(lane)) >> shift) & 0xFFFFu;
  }
  template <class Body>
  __device__ void for_each_lane(Body&& body) const {
    body(lane, 0);
  }
  // Lane l's partial sums, every float of them shuffled from l in turn and added in lane order.
  template <class Sums>
  __device__ Sums sum_in_lane_order(const Sums* held) const {
    static_assert(sizeof(Sums) % sizeof(float) == 0, "partial sums are floats");
    constexpr int kFloats = sizeof(Sums) / sizeof(float);
    float mine[kFloats];
    memcpy(mine, &held[0], sizeof(Sums));
    Sums total;
    for (int l = 0; l < kPairLanes; ++l) {
      float theirs[kFloats];
      for (int m = 0; m < kFloats; ++m) theirs[m] = __shfl_sync(members, mine[m], l, kPairLanes);
      Sums t;
      memcpy(&t, theirs, sizeof(Sums));
      add_lane_sums(total, t);
    }
    return total;
  }
};

// The passes that run on a HalfWarp team (pair_lanes.hpp), named by a tag like the per-thread ones.
template <bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>
struct FluidRatesLanes {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3], const HalfWarp& t) {
    update_fluid_rates_in_lanes<Kernel, Dim, Gamma7, Multiphase, MovingWalls, Riemann>(P, v, d, i, g, t);
  }
};
struct WallTemperatureLanes {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3], const HalfWarp& t) {
    update_wall_temperature_in_lanes<Kernel, Dim>(P, v, d, i, g, t);
  }
};
struct SpsStressLanes {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3], const HalfWarp& t) {
    update_sps_stress_in_lanes<Kernel, Dim>(P, v, d, i, g, t);
  }
};
struct SpsAccelerationLanes {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3], const HalfWarp& t) {
    add_sps_acceleration_in_lanes<Kernel, Dim>(P, v, d, i, g, t);
  }
};

// kPairLanes threads per particle of [first, first + count); blocks are whole warps, so a
// half-warp is 16 consecutive threads that share one particle and leave together.
template <class Update, class Kernel, int Dim>
__global__ void lanes_kernel(DeviceFields d, std::uint32_t first, std::uint32_t count, CellGridView v, Lattice L, PhysicsParams P) {
  const std::uint32_t k = thread_index() / kPairLanes;
  if (k >= count) return;
  const std::uint32_t i = first + k;
  const unsigned shift = threadIdx.x & 16u;
  const HalfWarp team{static_cast<int>(threadIdx.x & 15u), 0xFFFFu << shift, shift};
  int g[3];
  cell_coords<Dim>(L, d, i, g);
  Update::template run<Kernel, Dim>(P, v, d, i, g, team);
}

// Owned particles [first, first + count): the whole slab, or the interior or a boundary range.
// Extra arguments (the shifting pass's dt) go to the pass.
template <class Update, class Kernel, int Dim, class... Extra>
__global__ void neighbour_kernel(DeviceFields d, std::uint32_t first, std::uint32_t count, CellGridView v, Lattice L, PhysicsParams P,
                                 Extra... extra) {
  const std::uint32_t k = thread_index();
  if (k >= count) return;
  const std::uint32_t i = first + k;
  int g[3];
  cell_coords<Dim>(L, d, i, g);
  Update::template run<Kernel, Dim>(P, v, d, i, g, extra...);
}

// Per-particle stable step (infinity for walls); the minimum is a CUB reduction (order-free, exact).
__global__ void time_step_kernel(DeviceFields d, int dim, std::uint32_t n, PhysicsParams P, TimeStepControl c, float* out) {
  const std::uint32_t i = thread_index();
  if (i >= n) return;
  if (!P.is_fluid(d.material[i])) {
    out[i] = INFINITY;
    return;
  }
  float v2 = 0.0f, a2 = 0.0f;
  for (int k = 0; k < dim; ++k) {
    v2 += d.vel[k][i] * d.vel[k][i];
    a2 += d.acc[k][i] * d.acc[k][i];
  }
  out[i] = particle_time_step(P, P.materials.of(d.material[i]), c, sqrtf(v2), sqrtf(a2));
}

// The physics loops over the resident DeviceSlabArrays, on its compute stream. Kernels are queued
// without waiting; the host waits only where it needs a value (reductions, table reads, halo
// exchanges), which is what lets the interior pass run while the halo travels.
class CudaKernels final : public StepKernels {
 public:
  CudaKernels(int device, int dim) : arrays_(device, dim) {}
  const char* name() const override { return "cuda"; }
  SlabArrays& arrays() override { return arrays_; }

  // The rates of step n become the "previous" ones (ParticleStore::swap_rates, on the pointers).
  void predict(ParticleStore&, const PhysicsParams& P, float dt) override {
    arrays_.select();
    arrays_.swap_rates();
    launch(owned(), predict_kernel, arrays_.fields(), owned32(), dt, P);
  }
  void correct(ParticleStore&, const PhysicsParams& P, float dt) override {
    arrays_.select();
    launch(owned(), correct_kernel, arrays_.fields(), arrays_.dim(), owned32(), dt, P.density_mode == DensityMode::Continuity,
           P);
  }
  void equation_of_state(ParticleStore&, const PhysicsParams& P) override {
    arrays_.select();
    launch(arrays_.size(), eos_kernel, arrays_.fields(), static_cast<std::uint32_t>(arrays_.size()), P);
  }
  void summation_density(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    neighbour_pass<SummationDensityPass>(P, ParticleRange{0, owned()});
  }
  void wall_state(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    neighbour_pass<WallStatePass>(P, ParticleRange{0, owned()});
  }
  void fluid_rates_range(const CellGrid&, const PhysicsParams& P, ParticleRange range) override {
    // The same choices as dispatch_pair_loop on the CPU.
    dispatch_pair_flags(pair_loop_flags(P), [&]<bool Gamma7, bool Multiphase, bool MovingWalls, bool Riemann>() {
      if (per_thread_pair_loop_) {
        neighbour_pass<FluidRatesPass<Gamma7, Multiphase, MovingWalls, Riemann>>(P, range);
        return;
      }
      lanes_pass<FluidRatesLanes<Gamma7, Multiphase, MovingWalls, Riemann>>(P, range);
    });
  }
  void colour_gradient(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    neighbour_pass<ColourGradientPass>(P, ParticleRange{0, owned()});
  }
  void surface_tension(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    neighbour_pass<SurfaceTensionPass>(P, ParticleRange{0, owned()});
  }
  void density_gradient(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    neighbour_pass<DensityGradientPass>(P, ParticleRange{0, owned()});
  }
  void antuono_diffusion(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    neighbour_pass<AntuonoDiffusionPass>(P, ParticleRange{0, owned()});
  }
  void sps_stress(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    if (per_thread_pair_loop_) neighbour_pass<SpsStressPass>(P, ParticleRange{0, owned()});
    else lanes_pass<SpsStressLanes>(P, ParticleRange{0, owned()});
  }
  void sps_acceleration(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    if (per_thread_pair_loop_) neighbour_pass<SpsAccelerationPass>(P, ParticleRange{0, owned()});
    else lanes_pass<SpsAccelerationLanes>(P, ParticleRange{0, owned()});
  }
  void shifting(ParticleStore&, const CellGrid&, const PhysicsParams& P, float dt) override {
    neighbour_pass<ShiftingPass>(P, ParticleRange{0, owned()}, dt);
  }
  void shift_density(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    neighbour_pass<ShiftDensityPass>(P, ParticleRange{0, owned()});
  }
  // Heat transfer in the CPU's lane order (pair_lanes.hpp): the wall temperatures' fits on
  // half-warps; the fluid particles' conduction summed by the half-warp fluid pass, so that the heat
  // pass is left with the walls and solids that conduct (as the CPU's, cpu_backend.cpp).
  void wall_temperature(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    if (per_thread_pair_loop_) neighbour_pass<WallTemperaturePass>(P, ParticleRange{0, owned()});
    else lanes_pass<WallTemperatureLanes>(P, ParticleRange{0, owned()});
  }
  void heat_rates(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    const bool fused = !per_thread_pair_loop_ && fused_heat(P);
    if (fused && !P.heat.walls_conduct) return;  // the walls' rates stay 0 (update_heat_rates' value)
    neighbour_pass<HeatRatesPass>(P, ParticleRange{0, owned()}, fused);
  }
  float min_time_step(const ParticleStore&, const PhysicsParams& P, const TimeStepControl& c) override {
    arrays_.select();
    float dt = INFINITY;
    if (owned() > 0) {
      launch(owned(), time_step_kernel, arrays_.fields(), arrays_.dim(), owned32(), P, c, arrays_.scratch());
      dt = arrays_.min_f32(arrays_.scratch(), owned());
    }
    const float limit = state_free_time_step(P, c);
    return limit < dt ? limit : dt;
  }
  std::size_t device_bytes() const override { return arrays_.bytes(); }

  // Per-pass times (backend/pass_times.hpp) on the device's timeline: an event on the compute
  // stream at each end of a pass, resolved when asked (or, for the oldest half, when a thousand
  // are pending: long finished by then, so resolving them does not wait). A pass's time runs from
  // when the stream reaches its start to when it reaches its end, idle gaps included.
  void begin_pass(Pass) override {
    arrays_.select();
    open_event_ = take_event();
    check(cudaEventRecord(open_event_, arrays_.stream()), "cudaEventRecord");
  }
  void end_pass(Pass p) override {
    arrays_.select();
    cudaEvent_t end = take_event();
    check(cudaEventRecord(end, arrays_.stream()), "cudaEventRecord");
    timed_.push_back({p, open_event_, end});
    if (timed_.size() >= 1024) resolve_passes(timed_.size() / 2);
  }
  PassSeconds pass_seconds() override {
    arrays_.select();
    resolve_passes(timed_.size());
    return pass_seconds_;
  }
  ~CudaKernels() override {
    arrays_.select();
    for (const TimedPass& t : timed_) cudaEventDestroy(t.begin), cudaEventDestroy(t.end);
    for (cudaEvent_t e : event_pool_) cudaEventDestroy(e);
  }

 private:
  struct TimedPass {
    Pass pass;
    cudaEvent_t begin, end;
  };
  cudaEvent_t take_event() {
    if (!event_pool_.empty()) {
      cudaEvent_t e = event_pool_.back();
      event_pool_.pop_back();
      return e;
    }
    cudaEvent_t e = nullptr;
    check(cudaEventCreate(&e), "cudaEventCreate");
    return e;
  }
  // The first n timed passes: added to pass_seconds_, their events back to the pool.
  void resolve_passes(std::size_t n) {
    for (std::size_t k = 0; k < n; ++k) {
      const TimedPass& t = timed_[k];
      check(cudaEventSynchronize(t.end), "cudaEventSynchronize");
      float ms = 0.0f;
      check(cudaEventElapsedTime(&ms, t.begin, t.end), "cudaEventElapsedTime");
      pass_seconds_[static_cast<int>(t.pass)] += 1e-3 * ms;
      event_pool_.push_back(t.begin);
      event_pool_.push_back(t.end);
    }
    timed_.erase(timed_.begin(), timed_.begin() + static_cast<std::ptrdiff_t>(n));
  }

  std::size_t owned() const { return arrays_.owned(); }
  std::uint32_t owned32() const { return static_cast<std::uint32_t>(arrays_.owned()); }

  template <class Pass, class... Extra>
  void neighbour_pass(const PhysicsParams& P, ParticleRange range, Extra... extra) {
    arrays_.select();
    dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
      launch(range.count, neighbour_kernel<Pass, Kernel, Dim, Extra...>, arrays_.fields(), static_cast<std::uint32_t>(range.first),
             static_cast<std::uint32_t>(range.count), arrays_.view(), arrays_.lattice(), P, extra...);
    });
  }

  // A pass on HalfWarp teams: kPairLanes threads per particle of the range.
  template <class Pass>
  void lanes_pass(const PhysicsParams& P, ParticleRange range) {
    arrays_.select();
    dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
      launch(range.count * kPairLanes, lanes_kernel<Pass, Kernel, Dim>, arrays_.fields(), static_cast<std::uint32_t>(range.first),
             static_cast<std::uint32_t>(range.count), arrays_.view(), arrays_.lattice(), P);
    });
  }

  template <class... KernelArgs, class... Args>
  void launch(std::size_t items, void (*kernel)(KernelArgs...), Args&&... args) {
    if (items == 0) return;
    const LaunchShape s = launch_shape(items);
    kernel<<<s.blocks, s.threads, 0, arrays_.stream()>>>(std::forward<Args>(args)...);
    check(cudaGetLastError(), "kernel launch");
  }

  DeviceSlabArrays arrays_;
  // SPATE_GPU_PAIR_LOOP=thread: the fluid and SPS passes one thread per particle, its neighbours
  // summed in one sequence (the GPU's first loops, for comparison; within the GPU check's
  // tolerance of the CPU, not its bits). Otherwise the half-warp passes.
  bool per_thread_pair_loop_ = per_thread_pair_loop(std::getenv("SPATE_GPU_PAIR_LOOP"));
  cudaEvent_t open_event_ = nullptr;
  std::vector<TimedPass> timed_;
  std::vector<cudaEvent_t> event_pool_;
};

}  // namespace

std::unique_ptr<StepKernels> make_cuda_kernels(int device, int dim) { return std::make_unique<CudaKernels>(device, dim); }

}  // namespace spate::gpu
