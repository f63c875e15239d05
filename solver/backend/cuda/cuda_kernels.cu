// The CUDA driver: the same physics bodies as backend/cpu (solver/physics, SPATE_HD), one thread per
// particle, each summing its neighbours sequentially in the (cell, id) order of CellGridView, so
// there are no atomics and every sum is accumulated in the same order as on the CPU, whatever the
// split into slabs. Everything topological (migration, sort, halos) stays with the host worker
// (StepKernels); this file only keeps a device copy of the slab's fields and runs the loops.
#include <cub/device/device_reduce.cuh>
#include <cuda_runtime.h>

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
#include "../particle_updates.hpp"
#include "device_plan.hpp"
#include "device_runtime.hpp"

namespace spate::gpu {

namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

// The device arrays of one slab, by value into every kernel. Components beyond dim are null.
struct DeviceFields {
  float* pos[3];
  float* vel[3];
  float* acc[3];
  float* acc_prev[3];
  float* density;
  float* pressure;
  float* density_rate;
  float* density_rate_prev;
  const std::uint32_t* id;
  const std::uint8_t* kind;
};

// Global cell coordinates of particle i: the cell its (unchanged since the sort) position is in,
// which is the owned cell whose coordinates the CPU loop passes.
template <int Dim>
__device__ void cell_coords(const Lattice& L, const DeviceFields& d, std::uint32_t i, int g[3]) {
  g[0] = g[1] = g[2] = 0;
  for (int a = 0; a < Dim; ++a) g[a] = L.cell_of(d.pos[a][i], a);
}

__device__ std::uint32_t thread_index() { return blockIdx.x * blockDim.x + threadIdx.x; }

__global__ void predict_kernel(DeviceFields d, int dim, std::uint32_t n, float dt, bool continuity) {
  const std::uint32_t i = thread_index();
  if (i >= n || !is_fluid(d.kind[i])) return;
  for (int k = 0; k < dim; ++k) predict_component(d.pos[k][i], d.vel[k][i], d.acc_prev[k][i], dt);
  if (continuity) predict_density(d.density[i], d.density_rate_prev[i], dt);
}

__global__ void correct_kernel(DeviceFields d, int dim, std::uint32_t n, float dt, bool continuity) {
  const std::uint32_t i = thread_index();
  if (i >= n || !is_fluid(d.kind[i])) return;
  for (int k = 0; k < dim; ++k) correct(d.vel[k][i], d.acc[k][i], d.acc_prev[k][i], dt);
  if (continuity) correct(d.density[i], d.density_rate[i], d.density_rate_prev[i], dt);
}

__global__ void eos_kernel(DeviceFields d, std::uint32_t n, PhysicsParams P) {
  const std::uint32_t i = thread_index();
  if (i < n && is_fluid(d.kind[i])) d.pressure[i] = tait_pressure(d.density[i], P.rho0, P.tait_b);
}

// One thread per owned particle running one of the shared per-particle bodies
// (backend/particle_updates.hpp), named by a tag so that the three neighbour loops share one kernel.
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
struct FluidRatesPass {
  template <class Kernel, int Dim>
  __device__ static void run(const PhysicsParams& P, const CellGridView& v, DeviceFields& d, std::uint32_t i, const int g[3]) {
    update_fluid_rates<Kernel, Dim>(P, v, d, i, g);
  }
};

template <class Update, class Kernel, int Dim>
__global__ void neighbour_kernel(DeviceFields d, std::uint32_t owned, CellGridView v, Lattice L, PhysicsParams P) {
  const std::uint32_t i = thread_index();
  if (i >= owned) return;
  int g[3];
  cell_coords<Dim>(L, d, i, g);
  Update::template run<Kernel, Dim>(P, v, d, i, g);
}

// Per-particle stable step (infinity for walls); the minimum is a CUB reduction (order-free, exact).
__global__ void time_step_kernel(DeviceFields d, int dim, std::uint32_t n, PhysicsParams P, TimeStepControl c, float* out) {
  const std::uint32_t i = thread_index();
  if (i >= n) return;
  if (!is_fluid(d.kind[i])) {
    out[i] = INFINITY;
    return;
  }
  float v2 = 0.0f, a2 = 0.0f;
  for (int k = 0; k < dim; ++k) {
    v2 += d.vel[k][i] * d.vel[k][i];
    a2 += d.acc[k][i] * d.acc[k][i];
  }
  out[i] = particle_time_step(P, c, sqrtf(v2), sqrtf(a2));
}

// One device array per host field (same order as ParticleStore::fields()).
struct DeviceArray {
  std::string name;
  std::size_t elem_size = 0;
  char* data = nullptr;
};

class CudaKernels final : public StepKernels {
 public:
  CudaKernels(int device, int dim) : device_(device), dim_(dim) {
    select();
    check(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), "cudaStreamCreate");
    check(cudaMalloc(&dt_min_, sizeof(float)), "cudaMalloc(dt)");
  }
  ~CudaKernels() override {
    cudaSetDevice(device_);
    for (auto& a : arrays_) cudaFree(a.data);
    cudaFree(dt_scratch_);
    cudaFree(dt_min_);
    cudaFree(starts_);
    cudaFree(cub_temp_);
    cudaStreamDestroy(stream_);
  }
  CudaKernels(const CudaKernels&) = delete;
  CudaKernels& operator=(const CudaKernels&) = delete;

  const char* name() const override { return "cuda"; }

  // The rates of step n become the "previous" ones (ParticleStore::swap_rates, on the device
  // pointers); the host learns of it with the next fetch, which copies every field by name.
  void predict(ParticleStore&, const PhysicsParams& P, float dt) override {
    select();
    for (int k = 0; k < dim_; ++k) std::swap(arrays_[acc_[k]].data, arrays_[acc_prev_[k]].data);
    std::swap(arrays_[rate_].data, arrays_[rate_prev_].data);
    launch(owned_, predict_kernel, fields(), dim_, owned32(), dt, P.density_mode == DensityMode::Continuity);
  }
  void correct(ParticleStore&, const PhysicsParams& P, float dt) override {
    select();
    launch(owned_, correct_kernel, fields(), dim_, owned32(), dt, P.density_mode == DensityMode::Continuity);
  }
  void equation_of_state(ParticleStore&, const PhysicsParams& P) override {
    select();
    launch(size_, eos_kernel, fields(), static_cast<std::uint32_t>(size_), P);
  }
  void summation_density(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    select();
    dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
      launch(owned_, neighbour_kernel<SummationDensityPass, Kernel, Dim>, fields(), owned32(), view_, lattice_, P);
    });
  }
  void wall_state(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    select();
    dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
      launch(owned_, neighbour_kernel<WallStatePass, Kernel, Dim>, fields(), owned32(), view_, lattice_, P);
    });
  }
  void fluid_rates(ParticleStore&, const CellGrid&, const PhysicsParams& P) override {
    select();
    dispatch_kernel_dim(P, [&]<class Kernel, int Dim>() {
      launch(owned_, neighbour_kernel<FluidRatesPass, Kernel, Dim>, fields(), owned32(), view_, lattice_, P);
    });
  }
  float min_time_step(const ParticleStore&, const PhysicsParams& P, const TimeStepControl& c) override {
    select();
    float dt = INFINITY;
    if (owned_ > 0) {
      launch(owned_, time_step_kernel, fields(), dim_, owned32(), P, c, dt_scratch_);
      std::size_t bytes = 0;
      check(cub::DeviceReduce::Min(nullptr, bytes, dt_scratch_, dt_min_, static_cast<int>(owned_), stream_), "cub::DeviceReduce::Min");
      if (bytes > cub_temp_bytes_) {
        cudaFree(cub_temp_);
        check(cudaMalloc(&cub_temp_, bytes), "cudaMalloc(cub scratch)");
        cub_temp_bytes_ = bytes;
      }
      check(cub::DeviceReduce::Min(cub_temp_, bytes, dt_scratch_, dt_min_, static_cast<int>(owned_), stream_), "cub::DeviceReduce::Min");
      check(cudaMemcpyAsync(&dt, dt_min_, sizeof(float), cudaMemcpyDeviceToHost, stream_), "copy dt");
      check(cudaStreamSynchronize(stream_), "time step");
    }
    const float viscous = viscous_time_step(P, c);
    return viscous < dt ? viscous : dt;
  }

  void publish(const ParticleStore& host, const CellGrid& grid) override {
    select();
    auto& p = const_cast<ParticleStore&>(host);
    auto refs = p.fields();
    if (arrays_.empty()) name_arrays(refs);
    reserve(p.size());
    size_ = p.size();
    owned_ = p.owned();
    for (std::size_t f = 0; f < refs.size(); ++f)
      if (size_ > 0)
        check(cudaMemcpyAsync(arrays_[f].data, refs[f].bytes(), size_ * refs[f].elem_size, cudaMemcpyHostToDevice, stream_),
              "upload particles");
    const auto& starts = grid.starts();
    if (starts.size() > starts_capacity_) {
      cudaFree(starts_);
      starts_capacity_ = grown_capacity(starts.size(), 0);
      check(cudaMalloc(&starts_, starts_capacity_ * sizeof(std::uint32_t)), "cudaMalloc(cell table)");
    }
    check(cudaMemcpyAsync(starts_, starts.data(), starts.size() * sizeof(std::uint32_t), cudaMemcpyHostToDevice, stream_),
          "upload cell table");
    view_ = grid.view();
    view_.start = starts_;
    lattice_ = grid.lattice();
    check(cudaStreamSynchronize(stream_), "publish");
  }

  void publish_fields(const ParticleStore& host, FieldSet set, std::size_t first, std::size_t last) override {
    select();
    auto refs = const_cast<ParticleStore&>(host).fields();
    for (std::size_t f = 0; f < refs.size(); ++f)
      if (in_set(refs[f], set) && last > first)
        check(cudaMemcpyAsync(arrays_[f].data + first * refs[f].elem_size, refs[f].bytes() + first * refs[f].elem_size,
                              (last - first) * refs[f].elem_size, cudaMemcpyHostToDevice, stream_),
              "upload fields");
    check(cudaStreamSynchronize(stream_), "publish_fields");
  }

  void fetch(ParticleStore& p, FieldSet set, std::size_t first, std::size_t last) override {
    select();
    auto refs = p.fields();
    for (std::size_t f = 0; f < refs.size(); ++f)
      if (in_set(refs[f], set) && last > first)
        check(cudaMemcpyAsync(refs[f].bytes() + first * refs[f].elem_size, arrays_[f].data + first * refs[f].elem_size,
                              (last - first) * refs[f].elem_size, cudaMemcpyDeviceToHost, stream_),
              "download fields");
    check(cudaStreamSynchronize(stream_), "fetch");
  }

  std::size_t device_bytes() const override {
    return capacity_ * device_footprint(dim_).per_particle() + starts_capacity_ * sizeof(std::uint32_t) + cub_temp_bytes_;
  }

 private:
  void select() const { check(cudaSetDevice(device_), "cudaSetDevice"); }
  std::uint32_t owned32() const { return static_cast<std::uint32_t>(owned_); }

  template <class... KernelArgs, class... Args>
  void launch(std::size_t items, void (*kernel)(KernelArgs...), Args&&... args) {
    if (items == 0) return;
    const LaunchShape s = launch_shape(items);
    kernel<<<s.blocks, s.threads, 0, stream_>>>(std::forward<Args>(args)...);
    check(cudaGetLastError(), "kernel launch");
    check(cudaStreamSynchronize(stream_), "kernel");
  }

  void name_arrays(const std::vector<FieldRef>& refs) {
    for (auto& r : refs) arrays_.push_back({std::string(r.name), r.elem_size, nullptr});
    auto index = [&](std::string_view n) {
      for (std::size_t f = 0; f < arrays_.size(); ++f)
        if (arrays_[f].name == n) return static_cast<int>(f);
      throw std::logic_error("CudaKernels: the host store has no field " + std::string(n));
    };
    static constexpr std::string_view acc[3] = {"ax", "ay", "az"}, prev[3] = {"ax_prev", "ay_prev", "az_prev"},
                                      pos[3] = {"x", "y", "z"}, vel[3] = {"vx", "vy", "vz"};
    for (int k = 0; k < dim_; ++k) {
      pos_[k] = index(pos[k]);
      vel_[k] = index(vel[k]);
      acc_[k] = index(acc[k]);
      acc_prev_[k] = index(prev[k]);
    }
    density_ = index("density");
    pressure_ = index("pressure");
    rate_ = index("density_rate");
    rate_prev_ = index("density_rate_prev");
    id_ = index("id");
    kind_ = index("kind");
  }

  // Grows every array (keeping its first size_ entries) to hold n particles.
  void reserve(std::size_t n) {
    const std::size_t cap = grown_capacity(n, capacity_);
    if (cap == capacity_) return;
    for (auto& a : arrays_) {
      char* fresh = nullptr;
      check(cudaMalloc(&fresh, cap * a.elem_size), "cudaMalloc(particles)");
      if (a.data && size_ > 0) check(cudaMemcpyAsync(fresh, a.data, size_ * a.elem_size, cudaMemcpyDeviceToDevice, stream_), "grow");
      check(cudaStreamSynchronize(stream_), "grow");
      cudaFree(a.data);
      a.data = fresh;
    }
    cudaFree(dt_scratch_);
    check(cudaMalloc(&dt_scratch_, cap * sizeof(float)), "cudaMalloc(time step scratch)");
    capacity_ = cap;
  }

  DeviceFields fields() const {
    DeviceFields d{};
    auto f32 = [&](int f) { return reinterpret_cast<float*>(arrays_[f].data); };
    for (int k = 0; k < dim_; ++k) {
      d.pos[k] = f32(pos_[k]);
      d.vel[k] = f32(vel_[k]);
      d.acc[k] = f32(acc_[k]);
      d.acc_prev[k] = f32(acc_prev_[k]);
    }
    d.density = f32(density_);
    d.pressure = f32(pressure_);
    d.density_rate = f32(rate_);
    d.density_rate_prev = f32(rate_prev_);
    d.id = reinterpret_cast<const std::uint32_t*>(arrays_[id_].data);
    d.kind = reinterpret_cast<const std::uint8_t*>(arrays_[kind_].data);
    return d;
  }

  int device_, dim_;
  cudaStream_t stream_ = nullptr;
  std::vector<DeviceArray> arrays_;
  int pos_[3] = {0, 0, 0}, vel_[3] = {0, 0, 0}, acc_[3] = {0, 0, 0}, acc_prev_[3] = {0, 0, 0};
  int density_ = 0, pressure_ = 0, rate_ = 0, rate_prev_ = 0, id_ = 0, kind_ = 0;
  std::size_t capacity_ = 0, size_ = 0, owned_ = 0;
  std::uint32_t* starts_ = nullptr;
  std::size_t starts_capacity_ = 0;
  CellGridView view_{};
  Lattice lattice_{};
  float* dt_scratch_ = nullptr;
  float* dt_min_ = nullptr;
  void* cub_temp_ = nullptr;
  std::size_t cub_temp_bytes_ = 0;
};

}  // namespace

std::unique_ptr<StepKernels> make_cuda_kernels(int device, int dim) { return std::make_unique<CudaKernels>(device, dim); }

}  // namespace spate::gpu
