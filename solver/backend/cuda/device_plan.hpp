#pragma once
// The host-side arithmetic of the CUDA backend, kept free of CUDA so that the CPU test suite covers
// it: kernel launch shapes, device buffer capacities, the device memory a case needs per GPU, and
// which GPU each device worker drives.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "../../grid/lattice.hpp"
#include "../../particles/particle_pack.hpp"

namespace spate::gpu {

// One thread per particle (or per item), `threads` per block.
struct LaunchShape {
  unsigned blocks = 0;
  unsigned threads = 0;
};
constexpr unsigned kThreadsPerBlock = 128;
// blocks = ceil(items / threads); zero items gives zero blocks (the caller skips the launch).
// Throws std::length_error beyond the 2^31 - 1 blocks a grid's x dimension allows.
LaunchShape launch_shape(std::size_t items, unsigned threads = kThreadsPerBlock);

// The environment's SPATE_GPU_PAIR_LOOP: unset, empty or "lanes" gives the fluid pass a half-warp
// per particle in the CPU's lane order (false); "thread" one thread per particle, summing its
// neighbours in one sequence (true). Anything else throws std::invalid_argument naming it.
bool per_thread_pair_loop(const char* env);

// Device arrays grow with headroom (particles migrate in, ghosts vary step to step) so that a
// reallocation, which costs a cudaMalloc and a copy, is rare: at least needed + needed/8, rounded
// up to a multiple of kCapacityQuantum. They never shrink.
constexpr std::size_t kCapacityQuantum = 4096;
std::size_t grown_capacity(std::size_t needed, std::size_t current);

// Memory that grows, over an owning handle (`Owner`: std::unique_ptr-like, frees what it holds;
// the device's cudaMalloc/cudaMallocAsync/cudaMallocHost blocks, host memory in the tests) and an
// allocator (`allocate(bytes)` returns an Owner or throws). Written here, free of CUDA, so that
// the CPU tests check what happens when an allocation fails halfway.
template <class Owner>
struct Growable {
  Owner owner{};
  std::size_t bytes = 0;
  char* data() const { return owner.get(); }
  // At least n bytes, growing with headroom (grown_capacity); the contents are discarded. The
  // old block goes first (device memory is precious), and `bytes` says 0 until the new block is
  // there: if the allocation throws, the buffer is empty, not a size without memory.
  template <class Allocate>
  void reserve_discarding(std::size_t n, Allocate&& allocate) {
    if (n <= bytes) return;
    const std::size_t grown = grown_capacity(n, bytes);
    owner = Owner{};
    bytes = 0;
    owner = allocate(grown);
    bytes = grown;
  }
};

// Grows several blocks at once, keeping the first keep[k] bytes of block k, all or nothing: every
// new block is allocated, then filled (`copy(to, from, bytes)`, queued), then `wait()` for the
// copies, and only then are the old blocks replaced (and freed). An allocation or copy that throws
// leaves every block as it was, and what was already allocated is freed with `fresh`.
template <class Owner, class Allocate, class Copy, class Wait>
void grow_all_or_nothing(std::span<Owner* const> blocks, std::span<const std::size_t> bytes, std::span<const std::size_t> keep,
                         Allocate&& allocate, Copy&& copy, Wait&& wait) {
  std::vector<Owner> fresh;
  fresh.reserve(blocks.size());
  for (std::size_t k = 0; k < blocks.size(); ++k) fresh.push_back(allocate(bytes[k]));
  for (std::size_t k = 0; k < blocks.size(); ++k)
    if (keep[k] > 0 && blocks[k]->get() != nullptr) copy(fresh[k].get(), blocks[k]->get(), keep[k]);
  wait();
  for (std::size_t k = 0; k < blocks.size(); ++k) *blocks[k] = std::move(fresh[k]);
}

// What the device store holds per particle slot, in bytes (the fields mirror ParticleStore's).
struct DeviceFootprint {
  std::size_t field_bytes = 0;    // every registry field (field_registry.hpp), as on the host
  std::size_t sort_bytes = 0;     // the key, CUB's double-buffered (key, id) words and permutation
  std::size_t scratch_bytes = 0;  // one 4-byte word: gathers of the sort, reduction inputs
  std::size_t per_particle() const { return field_bytes + sort_bytes + scratch_bytes; }
};
DeviceFootprint device_footprint(int dim);
// Bytes of one particle's fields of `set` in a halo or migration buffer (FieldSet order of
// ParticleStore::fields()).
std::size_t staged_bytes(int dim, FieldSet set);
// Per halo ghost besides its slot: its Ghost fields in the sender's outgoing and the receiver's
// incoming device buffer, and its slot index for the refresh.
std::size_t halo_bytes_per_ghost(int dim);
// CUB's temporary storage for the sort, scans and reductions of `slots` particles: an upper
// estimate (the real size is asked from CUB at run time and grows the buffer when needed).
std::size_t cub_scratch_estimate(std::size_t slots);

// The 64-bit word the radix sort orders by (key, id): key << id_bits | id, with just enough bits
// for ids below `id_bound` (the largest id + 1 of the run) and keys below `key_count`; the sort
// looks at bits [0, end_bit) only, so narrower words take fewer radix passes.
struct SortWord {
  int id_bits = 32;
  int end_bit = 64;
};
int bits_for(std::uint64_t values);  // bits that hold 0 ... values - 1
SortWord sort_word(std::uint32_t key_count, std::uint32_t id_bound);

// How far a GPU run may be from the CPU run of the same case after the few hundred steps the GPU
// check takes, as a fraction of each field's scale (io/field_scale.hpp: dp, c0, rho0, c0^2/h,
// rho0 c0/h). They differ in the last bits (the CPU's fluid loop sums the neighbours into 16
// lanes, a CUDA thread in one sequence; powf in tait_density), and the differences grow with the
// steps. The CPU run in the GPU's summation order stays within a quarter of it on the cases the
// check compares (GpuOrder.* in tests/unit/test_step_kernels.cpp), where a wrong neighbour, ghost
// or image moves positions by far more.
constexpr double kGpuCpuScaledTolerance = 2e-4;

// The device memory one GPU needs for its slab: its share of the particles (uniform split of the
// x columns, particles spread evenly over columns: an estimate, balancing moves faces), the two
// ghost columns and their halo buffers, the cell table, capacity headroom and the CUB scratch.
struct SlabMemory {
  int slab = 0;
  int columns = 0;
  std::int64_t owned = 0;
  std::int64_t ghosts = 0;
  std::int64_t cells = 0;
  std::size_t capacity = 0;  // particle slots allocated
  std::size_t bytes = 0;
};
std::vector<SlabMemory> device_memory_per_slab(const Lattice& lattice, std::int64_t particles, int devices);

// CUDA_VISIBLE_DEVICES as the CUDA runtime reads it: a comma-separated list of indices or
// GPU-/MIG- UUIDs; the runtime ignores everything from the first entry it cannot parse (so "-1"
// or "" hides every device). Unset: nullopt (every device is visible).
std::optional<std::vector<std::string>> visible_devices(const char* env);
// A sentence for the "no CUDA device" error that says why none may be visible.
std::string no_device_reason(const char* env);

// The GPU (an index among the visible ones) that device worker `worker` of this process drives:
// processes on one node take consecutive blocks of devices (local_rank * workers_per_process),
// wrapping around when there are more workers than GPUs (shared GPUs: correct, but slower).
int device_for_worker(int worker, int workers_per_process, int local_rank, int visible_devices);
// This process's rank among the processes of its node, from the launcher's environment (Open MPI,
// MPICH/Hydra, MVAPICH2, Slurm); 0 when started without one. `getenv` is injectable for tests.
int node_local_rank(const char* (*getenv)(const char*) = nullptr);

}  // namespace spate::gpu
