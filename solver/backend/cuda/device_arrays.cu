// The SlabArrays primitives on the device (see device_arrays.cuh). Each primitive is a CUB call, a
// cudaMemcpy*Async of contiguous ranges, or a kernel of a few lines; none decides what to move
// (that is SlabTopology's, tested on the CPU). Sums are never done with atomics: the sort is a
// radix sort, the cell table a binary search per cell, compactions a CUB exclusive scan, the
// reductions CUB minima over integers or floats (exact, order-free).
#include "device_arrays.cuh"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

#include "../../physics/params.hpp"
#include "device_plan.hpp"
#include "device_runtime.hpp"

namespace spate::gpu {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

namespace {
DeviceMemory device_alloc(std::size_t bytes) {
  void* p = nullptr;
  check(cudaMalloc(&p, bytes), "cudaMalloc");
  return DeviceMemory(static_cast<char*>(p));
}
}  // namespace

void DeviceBuffer::reserve(std::size_t n, cudaStream_t in_use) {
  if (n <= bytes) return;
  check(cudaStreamSynchronize(in_use), "buffer growth");  // nothing may still read the old block
  reserve_discarding(n, device_alloc);
}
void StreamOrderedBuffer::reserve(std::size_t n, cudaStream_t stream) {
  reserve_discarding(n, [stream](std::size_t b) {
    void* p = nullptr;
    check(cudaMallocAsync(&p, b, stream), "cudaMallocAsync");
    return StreamOrderedMemory(static_cast<char*>(p), StreamOrderedFree{stream});
  });
}
void PinnedBuffer::reserve(std::size_t n) {
  reserve_discarding(n, [](std::size_t b) {
    void* p = nullptr;
    check(cudaMallocHost(&p, b), "cudaMallocHost");
    return PinnedMemory(static_cast<char*>(p));
  });
}

namespace {

__device__ std::uint32_t thread_index() { return blockIdx.x * blockDim.x + threadIdx.x; }

constexpr std::uint32_t kNone = SlabArrays::kNoFault;  // "no faulty particle" in the reductions

template <class... Params, class... Args>
void launch(cudaStream_t s, std::size_t items, void (*kernel)(Params...), Args... args) {
  if (items == 0) return;
  const LaunchShape shape = launch_shape(items);
  kernel<<<shape.blocks, shape.threads, 0, s>>>(args...);
  check(cudaGetLastError(), "kernel launch");
}

__global__ void key_kernel(std::uint32_t* keys, const float* x, const float* y, const float* z, CellGridView g, Lattice L,
                           const std::int8_t* hops, std::uint32_t first, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k >= n) return;
  const std::uint32_t i = first + k;
  keys[i] = particle_key(g, L, hops, x[i], y ? y[i] : 0.0f, z ? z[i] : 0.0f);
}

// (key, id) as one 64-bit word (SortWord); the values are the positions in the range (the
// permutation).
__global__ void compose_kernel(const std::uint32_t* keys, const std::uint32_t* id, int id_bits, std::uint64_t* words,
                               std::uint32_t* values, std::uint32_t first, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k >= n) return;
  words[k] = static_cast<std::uint64_t>(keys[first + k]) << id_bits | id[first + k];
  values[k] = k;
}

__global__ void key_of_word_kernel(const std::uint64_t* words, int id_bits, std::uint32_t* keys, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k < n) keys[k] = static_cast<std::uint32_t>(words[k] >> id_bits);
}

template <class T>
__global__ void gather_kernel(const T* src, const std::uint32_t* index, T* dst, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k < n) dst[k] = src[index[k]];
}

// The first particle of every key bin: a lower bound per bin in the sorted keys.
__global__ void table_kernel(const std::uint32_t* keys, std::uint32_t n, std::uint32_t* table, std::uint32_t entries) {
  const std::uint32_t b = thread_index();
  if (b >= entries) return;
  std::uint32_t lo = 0, hi = n;
  while (lo < hi) {
    const std::uint32_t mid = lo + (hi - lo) / 2;
    if (keys[mid] < b) lo = mid + 1;
    else hi = mid;
  }
  table[b] = lo;
}

__global__ void shift_kernel(float* x, std::uint32_t n, Shift shift) {
  const std::uint32_t k = thread_index();
  if (k < n) x[k] = shift.apply(x[k]);
}

__global__ void scatter_kernel(const float* src, const std::uint32_t* slots, float* dst, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k < n) dst[slots[k]] = src[k];
}

__global__ void copy_within_kernel(float* f, const std::uint32_t* source, const std::uint32_t* target, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k < n) f[target[k]] = f[source[k]];
}

// 1 for the particles in cell layer `layer` along `axis` whose x column is owned (local) or not.
__global__ void layer_flag_kernel(const float* x0, const float* x, Lattice L, int axis, int layer, int owned_lo, int owned_hi,
                                  bool local, std::uint32_t* flags, std::uint32_t n) {
  const std::uint32_t i = thread_index();
  if (i >= n) return;
  const int column = L.cell_of(x0[i], 0);
  const bool owned = column >= owned_lo && column < owned_hi;
  flags[i] = L.cell_of(x[i], axis) == layer && owned == local ? 1u : 0u;
}

__global__ void compact_kernel(const std::uint32_t* flags, const std::uint32_t* prefix, std::uint32_t* out, std::uint32_t n) {
  const std::uint32_t i = thread_index();
  if (i < n && flags[i]) out[prefix[i]] = i;
}

__global__ void iota_kernel(std::uint32_t* out, std::uint32_t first, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k < n) out[k] = first + k;
}

__global__ void inverse_kernel(const std::uint32_t* perm, std::uint32_t* slot_of, std::uint32_t owned, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k < n) slot_of[perm[k]] = owned + k;
}

__global__ void map_slots_kernel(std::uint32_t* list, const std::uint32_t* slot_of, std::uint32_t owned, std::uint32_t n) {
  const std::uint32_t k = thread_index();
  if (k < n && list[k] >= owned) list[k] = slot_of[list[k] - owned];
}

// Per owned particle: its id if a coordinate is faulty after wrapping, else kNoFault.
__global__ void position_fault_kernel(DeviceFields d, Lattice L, std::uint32_t n, std::uint32_t* out) {
  const std::uint32_t i = thread_index();
  if (i >= n) return;
  bool bad = false;
  for (int a = 0; a < L.dim; ++a) {
    wrap_periodic(L, d.pos[a][i], a);
    bad = bad || position_fault(L, d.pos[a][i], a) != PositionFault::None;
  }
  out[i] = bad ? d.id[i] : kNone;
}

// 1 for an owned fluid particle that left through an open side, else 0.
__global__ void escaped_flag_kernel(DeviceFields d, int dim, OpenSides o, std::uint32_t n, std::uint32_t* flags) {
  const std::uint32_t i = thread_index();
  if (i >= n) return;
  float x[3] = {0, 0, 0};
  for (int a = 0; a < dim; ++a) x[a] = d.pos[a][i];
  flags[i] = escaped(o, dim, d.material[i], x) ? 1u : 0u;
}

// Per particle: its id if it is not below `bound`, else kNoFault.
__global__ void id_not_below_kernel(const std::uint32_t* id, std::uint32_t bound, std::uint32_t n, std::uint32_t* out) {
  const std::uint32_t i = thread_index();
  if (i < n) out[i] = id[i] >= bound ? id[i] : kNone;
}

__global__ void health_kernel(DeviceFields d, int dim, HealthLimits h, std::uint32_t n, std::uint32_t* out) {
  const std::uint32_t i = thread_index();
  if (i >= n) return;
  float x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
  for (int a = 0; a < dim; ++a) x[a] = d.pos[a][i], v[a] = d.vel[a][i];
  const bool ok = !h.checked(d.material[i]) || healthy(h, state_finite(dim, x, v, d.density[i]), d.density[i], d.material[i]);
  out[i] = ok ? kNone : d.id[i];
}

std::uint32_t u32(std::size_t n) { return static_cast<std::uint32_t>(n); }

}  // namespace

#if defined(SPATE_CUDA_AWARE_MPI)
constexpr bool kCudaAwareMpi = true;
#else
constexpr bool kCudaAwareMpi = false;
#endif

DeviceSlabArrays::DeviceSlabArrays(int device, int dim)
    : device_(device), dim_(dim), halo_(kCudaAwareMpi, staged_links_forced(std::getenv("SPATE_CUDA_HALO_LINK"))) {
  // Every resource goes into an owning member as soon as it exists: a failure further down
  // releases what was made (the destructor does not run for a constructor that throws).
  select();
  cudaStream_t s = nullptr;
  check(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking), "cudaStreamCreate(compute)");
  compute_.reset(s);
  check(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking), "cudaStreamCreate(copy)");
  copy_.reset(s);
  cudaEvent_t e = nullptr;
  check(cudaEventCreateWithFlags(&e, cudaEventDisableTiming), "cudaEventCreate");
  staged_.reset(e);
  check(cudaEventCreateWithFlags(&e, cudaEventDisableTiming), "cudaEventCreate");
  consumed_.reset(e);
  check(cudaEventRecord(consumed_.get(), compute_.get()), "cudaEventRecord");
  result_ = device_alloc(2 * sizeof(std::uint32_t));
  result_host_.reserve(64);
  ParticleStore layout(dim);
  for (auto& f : layout.fields()) arrays_.push_back({f, nullptr});
}

// The members free the memory and then the events and streams; first nothing may still run.
DeviceSlabArrays::~DeviceSlabArrays() {
  cudaSetDevice(device_);
  cudaStreamSynchronize(compute_.get());
  cudaStreamSynchronize(copy_.get());
}

void DeviceSlabArrays::select() const { check(cudaSetDevice(device_), "cudaSetDevice"); }

int DeviceSlabArrays::index_of(int field, int component) const {
  for (std::size_t f = 0; f < arrays_.size(); ++f)
    if (arrays_[f].meta.spec == &kParticleFields[field] && arrays_[f].meta.component == component) return static_cast<int>(f);
  throw std::logic_error("DeviceSlabArrays: no array for component " + std::to_string(component) + " of field " +
                         std::string(kParticleFields[field].member));
}

namespace {
// Binds a DeviceFields member to the next array(s) of ParticleStore::fields() order.
template <class T>
void bind(T*& p, const char* const* data, std::size_t& at, int) {
  p = reinterpret_cast<T*>(const_cast<char*>(data[at++]));
}
template <class T>
void bind(T* (&p)[3], const char* const* data, std::size_t& at, int dim) {
  for (int k = 0; k < 3; ++k) p[k] = k < dim ? reinterpret_cast<T*>(const_cast<char*>(data[at++])) : nullptr;
}
}  // namespace

// The registry's fields come first in arrays_, in registry order, dim components per vector
// (ParticleStore::fields()); run-time extensions follow and have no DeviceFields member. An
// optional field the run does not carry (kOptional) stays a null pointer.
DeviceFields DeviceSlabArrays::fields() const {
  std::vector<const char*> data(arrays_.size());
  for (std::size_t f = 0; f < arrays_.size(); ++f) data[f] = arrays_[f].data.get();
  DeviceFields d{};
  std::size_t at = 0;
#define SPATE_BIND_FIELD(member, ...) \
  if (at < arrays_.size() && arrays_[at].meta.spec == &kParticleFields[kField_##member]) bind(d.member, data.data(), at, dim_);
  SPATE_PARTICLE_FIELDS(SPATE_BIND_FIELD)
#undef SPATE_BIND_FIELD
  return d;
}

void DeviceSlabArrays::swap_rates() {
  for (int k = 0; k < dim_; ++k) std::swap(arrays_[index_of(kField_acc, k)].data, arrays_[index_of(kField_acc_prev, k)].data);
  std::swap(arrays_[index_of(kField_density_rate, 0)].data, arrays_[index_of(kField_density_rate_prev, 0)].data);
  const bool heat = std::any_of(arrays_.begin(), arrays_.end(), [](const auto& a) { return a.meta.spec == &kParticleFields[kField_temperature_rate]; });
  if (heat) std::swap(arrays_[index_of(kField_temperature_rate, 0)].data, arrays_[index_of(kField_temperature_rate_prev, 0)].data);
}

// Grows every per-slot array, keeping the fields and keys of [0, size_); the sort buffers and the
// scratch word are rewritten by every use. The buffers that keep nothing go first; then the
// fields and keys all or nothing (grow_all_or_nothing): a failed allocation leaves the slab as it
// was, with its old capacity.
void DeviceSlabArrays::reserve(std::size_t n) {
  const std::size_t cap = grown_capacity(n, capacity_);
  if (cap == capacity_) return;
  for (auto& b : sort_keys_) b.reserve(cap * sizeof(std::uint64_t), compute_.get());
  for (auto& b : sort_values_) b.reserve(cap * sizeof(std::uint32_t), compute_.get());
  scratch_.reserve(cap * sizeof(std::uint32_t), compute_.get());
  std::vector<DeviceMemory*> blocks;
  std::vector<std::size_t> bytes, keep;
  for (auto& a : arrays_) {
    blocks.push_back(&a.data);
    bytes.push_back(cap * a.meta.elem_size);
    keep.push_back(size_ * a.meta.elem_size);
  }
  blocks.push_back(&keys_);
  bytes.push_back(cap * sizeof(std::uint32_t));
  keep.push_back(size_ * sizeof(std::uint32_t));
  check(cudaStreamSynchronize(compute_.get()), "growth");
  grow_all_or_nothing<DeviceMemory>(
      blocks, bytes, keep, device_alloc,
      [&](char* to, const char* from, std::size_t b) {
        check(cudaMemcpyAsync(to, from, b, cudaMemcpyDeviceToDevice, compute_.get()), "grow");
      },
      [&] { check(cudaStreamSynchronize(compute_.get()), "grow"); });
  capacity_ = cap;
}

void* DeviceSlabArrays::cub_scratch(std::size_t bytes) {
  cub_.reserve(bytes, compute_.get());
  return cub_.data();
}

std::size_t DeviceSlabArrays::bytes() const {
  std::size_t b = 0;
  for (auto& a : arrays_) b += capacity_ * a.meta.elem_size;
  b += capacity_ * sizeof(std::uint32_t);  // keys
  for (const DeviceBuffer* x : {&sort_keys_[0], &sort_keys_[1], &sort_values_[0], &sort_values_[1], &scratch_, &cub_, &table_, &hops_,
                                &outbox_[0], &outbox_[1], &slots_[0], &slots_[1]})
    b += x->bytes;
  for (auto& x : inbox_) b += x.bytes;
  for (auto& x : image_source_) b += x.bytes;
  for (auto& x : image_target_) b += x.bytes;
  return b;
}

std::uint32_t DeviceSlabArrays::min_u32(const std::uint32_t* in, std::size_t n) {
  if (n == 0) return kNoFault;
  std::size_t bytes = 0;
  check(cub::DeviceReduce::Min(nullptr, bytes, in, result(), static_cast<int>(n), compute_.get()), "cub::DeviceReduce::Min");
  check(cub::DeviceReduce::Min(cub_scratch(bytes), bytes, in, result(), static_cast<int>(n), compute_.get()), "cub::DeviceReduce::Min");
  check(cudaMemcpyAsync(result_host_.data(), result(), sizeof(std::uint32_t), cudaMemcpyDeviceToHost, compute_.get()), "copy minimum");
  check(cudaStreamSynchronize(compute_.get()), "minimum");
  std::uint32_t v;
  std::memcpy(&v, result_host_.data(), sizeof v);
  return v;
}

float DeviceSlabArrays::min_f32(const float* in, std::size_t n) {
  float* out = reinterpret_cast<float*>(result());
  std::size_t bytes = 0;
  check(cub::DeviceReduce::Min(nullptr, bytes, in, out, static_cast<int>(n), compute_.get()), "cub::DeviceReduce::Min");
  check(cub::DeviceReduce::Min(cub_scratch(bytes), bytes, in, out, static_cast<int>(n), compute_.get()), "cub::DeviceReduce::Min");
  check(cudaMemcpyAsync(result_host_.data(), out, sizeof(float), cudaMemcpyDeviceToHost, compute_.get()), "copy minimum");
  check(cudaStreamSynchronize(compute_.get()), "minimum");
  float v;
  std::memcpy(&v, result_host_.data(), sizeof v);
  return v;
}

// ---- host copies --------------------------------------------------------------------------------

void DeviceSlabArrays::set_id_bound(std::uint32_t bound) {
  select();
  if (size_ > 0) {  // the particles already here must fit the new bound too
    launch(compute_.get(), size_, id_not_below_kernel, static_cast<const std::uint32_t*>(fields().id), bound, u32(size_),
           scratch_.as<std::uint32_t>());
    const std::uint32_t lowest = min_u32(scratch_.as<const std::uint32_t>(), size_);
    if (lowest != kNoFault) throw_id_not_below(lowest, bound);
  }
  id_bound_ = bound;
}

void DeviceSlabArrays::upload(const ParticleStore& host) {
  select();
  require_ids_below(host.id, id_bound_);  // ids enter the device only here; they never change
  auto& p = const_cast<ParticleStore&>(host);
  auto refs = p.fields();
  reserve(p.size());
  size_ = p.size();
  owned_ = p.owned();
  std::size_t total = 0;
  for (auto& r : refs) total += size_ * r.elem_size;
  mirror_.reserve(total);
  std::size_t at = 0;
  for (std::size_t f = 0; f < refs.size(); ++f) {
    const std::size_t b = size_ * refs[f].elem_size;
    if (b == 0) continue;
    std::memcpy(mirror_.data() + at, refs[f].bytes(), b);
    check(cudaMemcpyAsync(arrays_[f].data.get(), mirror_.data() + at, b, cudaMemcpyHostToDevice, compute_.get()), "upload particles");
    at += b;
  }
  check(cudaStreamSynchronize(compute_.get()), "upload");
}

// The pinned mirror: every copy queued at once on the copy stream after the compute stream's work,
// one wait, then into the host store.
void DeviceSlabArrays::download(ParticleStore& host, CellGrid& grid) {
  select();
  if (host.dim() != dim_) throw std::logic_error("DeviceSlabArrays::download: a store of another dimension");
  // The host grid's part of the table of the last build_table; `grid` must still have its
  // geometry (checked before anything is copied).
  const std::size_t cells = table_entries_ > 0 ? view_.cell_count() + 1 : 0;
  if (cells > 0) grid.require_geometry(view_, cells);
  host.resize(size_);
  host.set_owned(owned_);
  auto refs = host.fields();
  std::size_t total = cells * sizeof(std::uint32_t);
  for (auto& r : refs) total += (in_set(r, FieldSet::Ghost) ? size_ : owned_) * r.elem_size;
  mirror_.reserve(total);
  check(cudaEventRecord(staged_.get(), compute_.get()), "cudaEventRecord");
  check(cudaStreamWaitEvent(copy_.get(), staged_.get(), 0), "cudaStreamWaitEvent");
  std::size_t at = 0;
  std::vector<std::size_t> offset(refs.size());
  for (std::size_t f = 0; f < refs.size(); ++f) {
    offset[f] = at;
    const std::size_t b = (in_set(refs[f], FieldSet::Ghost) ? size_ : owned_) * refs[f].elem_size;
    if (b > 0) check(cudaMemcpyAsync(mirror_.data() + at, arrays_[f].data.get(), b, cudaMemcpyDeviceToHost, copy_.get()), "download particles");
    at += b;
  }
  if (cells > 0) check(cudaMemcpyAsync(mirror_.data() + at, table_.data(), cells * sizeof(std::uint32_t), cudaMemcpyDeviceToHost, copy_.get()), "download table");
  check(cudaStreamSynchronize(copy_.get()), "download");
  for (std::size_t f = 0; f < refs.size(); ++f) {
    const std::size_t b = (in_set(refs[f], FieldSet::Ghost) ? size_ : owned_) * refs[f].elem_size;
    if (b > 0) std::memcpy(refs[f].bytes(), mirror_.data() + offset[f], b);
  }
  if (cells > 0) grid.assign_starts(view_, std::span(reinterpret_cast<const std::uint32_t*>(mirror_.data() + at), cells));
}

// ---- keys, sort, table --------------------------------------------------------------------------

void DeviceSlabArrays::truncate(std::size_t n) {
  size_ = std::min(size_, n);
  owned_ = std::min(owned_, n);
}

void DeviceSlabArrays::set_migration_hops(const std::vector<std::int8_t>& hops) {
  select();
  hops_.reserve(hops.size(), compute_.get());
  check(cudaMemcpyAsync(hops_.data(), hops.data(), hops.size(), cudaMemcpyHostToDevice, compute_.get()), "upload hops");
  check(cudaStreamSynchronize(compute_.get()), "upload hops");  // `hops` is pageable and may go away
}

void DeviceSlabArrays::compute_keys(const CellGrid& geometry, std::size_t first, std::size_t last, bool migrating) {
  select();
  CellGridView g = geometry.view();
  g.start = nullptr;
  lattice_ = geometry.lattice();
  key_count_ = KeyBins{g.cell_count()}.count();
  const DeviceFields d = fields();
  launch(compute_.get(), last - first, key_kernel, keys(), d.pos[0], dim_ >= 2 ? d.pos[1] : nullptr,
         dim_ >= 3 ? d.pos[2] : nullptr, g, lattice_, migrating ? hops_.as<const std::int8_t>() : nullptr, u32(first),
         u32(last - first));
}

void DeviceSlabArrays::sort_by_key(std::size_t first, std::size_t last) {
  select();
  const std::size_t n = last - first;
  sort_first_ = first;
  sort_count_ = n;
  if (n == 0) return;
  const SortWord word = sort_word(key_count_, id_bound_);
  launch(compute_.get(), n, compose_kernel, static_cast<const std::uint32_t*>(keys()), static_cast<const std::uint32_t*>(fields().id),
         word.id_bits, sort_keys_[0].as<std::uint64_t>(), sort_values_[0].as<std::uint32_t>(), u32(first), u32(n));
  cub::DoubleBuffer<std::uint64_t> words(sort_keys_[0].as<std::uint64_t>(), sort_keys_[1].as<std::uint64_t>());
  cub::DoubleBuffer<std::uint32_t> perm(sort_values_[0].as<std::uint32_t>(), sort_values_[1].as<std::uint32_t>());
  const int end_bit = word.end_bit;
  std::size_t bytes = 0;
  check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, words, perm, static_cast<int>(n), 0, end_bit, compute_.get()), "cub::DeviceRadixSort");
  check(cub::DeviceRadixSort::SortPairs(cub_scratch(bytes), bytes, words, perm, static_cast<int>(n), 0, end_bit, compute_.get()),
        "cub::DeviceRadixSort");
  sorted_values_ = perm.selector;
  // Every field follows the permutation: gathered into the scratch word, copied back.
  for (auto& a : arrays_) {
    if (a.meta.spec->scratch()) continue;
    char* at = a.data.get() + first * a.meta.elem_size;
    if (a.meta.elem_size == 4)
      launch(compute_.get(), n, gather_kernel<std::uint32_t>, reinterpret_cast<const std::uint32_t*>(at), perm.Current(),
             scratch_.as<std::uint32_t>(), u32(n));
    else if (a.meta.elem_size == 1)
      launch(compute_.get(), n, gather_kernel<std::uint8_t>, reinterpret_cast<const std::uint8_t*>(at), perm.Current(),
             scratch_.as<std::uint8_t>(), u32(n));
    else
      throw std::logic_error("DeviceSlabArrays: fields are 4 or 1 bytes wide");
    check(cudaMemcpyAsync(at, scratch_.data(), n * a.meta.elem_size, cudaMemcpyDeviceToDevice, compute_.get()), "permute");
  }
  launch(compute_.get(), n, key_of_word_kernel, static_cast<const std::uint64_t*>(words.Current()), word.id_bits,
         keys() + first, u32(n));
}

void DeviceSlabArrays::build_table(const CellGrid& geometry) {
  select();
  view_ = geometry.view();
  lattice_ = geometry.lattice();
  const std::uint32_t entries = KeyBins{view_.cell_count()}.table_entries();
  table_.reserve(entries * sizeof(std::uint32_t), compute_.get());
  launch(compute_.get(), entries, table_kernel, static_cast<const std::uint32_t*>(keys()), u32(size_), table_.as<std::uint32_t>(), entries);
  view_.start = table_.as<const std::uint32_t>();
  table_entries_ = entries;
}

std::vector<std::uint32_t> DeviceSlabArrays::table_entries(const TableRead& read) {
  select();
  std::vector<std::uint32_t> out(read.count);
  if (read.count == 0) return out;
  if (read.first + static_cast<std::size_t>(read.count - 1) * read.stride >= table_entries_)
    throw std::logic_error("DeviceSlabArrays: table read past the end");
  result_host_.reserve(read.count * sizeof(std::uint32_t));
  // A strided read of the table: one 4-byte column of a pitched 2D copy.
  check(cudaMemcpy2DAsync(result_host_.data(), sizeof(std::uint32_t), table_.as<std::uint32_t>() + read.first,
                          read.stride * sizeof(std::uint32_t), sizeof(std::uint32_t), read.count, cudaMemcpyDeviceToHost, compute_.get()),
        "read table");
  check(cudaStreamSynchronize(compute_.get()), "read table");
  std::memcpy(out.data(), result_host_.data(), read.count * sizeof(std::uint32_t));
  return out;
}

// The exclusive prefix sum of n 0/1 flags (a compaction's target slots) and their total, read back.
std::size_t DeviceSlabArrays::scan_flags(const std::uint32_t* flags, std::uint32_t* prefix, std::size_t n) {
  std::size_t bytes = 0;
  check(cub::DeviceScan::ExclusiveSum(nullptr, bytes, flags, prefix, static_cast<int>(n), compute_.get()), "cub::DeviceScan");
  check(cub::DeviceScan::ExclusiveSum(cub_scratch(bytes), bytes, flags, prefix, static_cast<int>(n), compute_.get()), "cub::DeviceScan");
  check(cudaMemcpyAsync(result_host_.data(), prefix + n - 1, sizeof(std::uint32_t), cudaMemcpyDeviceToHost, compute_.get()), "flag count");
  check(cudaMemcpyAsync(result_host_.data() + 4, flags + n - 1, sizeof(std::uint32_t), cudaMemcpyDeviceToHost, compute_.get()), "flag count");
  check(cudaStreamSynchronize(compute_.get()), "flag count");
  std::uint32_t last_prefix, last_flag;
  std::memcpy(&last_prefix, result_host_.data(), 4);
  std::memcpy(&last_flag, result_host_.data() + 4, 4);
  return std::size_t{last_prefix} + last_flag;
}

// ---- neighbour payload --------------------------------------------------------------------------

// Fields of `set` of particles from[0 .. count) written to slots [to, to + count), shifted.
void DeviceSlabArrays::gather_fields(FieldSet set, const std::uint32_t* from, std::size_t count, std::size_t to, Shift shift) {
  for (std::size_t f = 0; f < arrays_.size(); ++f) {
    Array& a = arrays_[f];
    if (!in_set(a.meta, set)) continue;
    char* dst = a.data.get() + to * a.meta.elem_size;
    if (a.meta.elem_size == 4)
      launch(compute_.get(), count, gather_kernel<std::uint32_t>, reinterpret_cast<const std::uint32_t*>(a.data.get()), from,
             reinterpret_cast<std::uint32_t*>(dst), u32(count));
    else
      launch(compute_.get(), count, gather_kernel<std::uint8_t>, reinterpret_cast<const std::uint8_t*>(a.data.get()), from,
             reinterpret_cast<std::uint8_t*>(dst), u32(count));
    if (shift.axis >= 0 && a.meta.spec == &kParticleFields[kField_pos] && a.meta.component == shift.axis)
      launch(compute_.get(), count, shift_kernel, reinterpret_cast<float*>(dst), u32(count), shift);
  }
}

void DeviceSlabArrays::zero_fields_outside(FieldSet set, std::size_t first, std::size_t count) {
  if (count == 0) return;
  for (auto& a : arrays_)
    if (!in_set(a.meta, set))
      check(cudaMemsetAsync(a.data.get() + first * a.meta.elem_size, 0, count * a.meta.elem_size, compute_.get()), "zero fields");
}

void DeviceSlabArrays::stage(Side side, FieldSet set, ParticleRange range, Shift shift) {
  select();
  std::size_t bytes = 0;
  for (auto& a : arrays_)
    if (in_set(a.meta, set)) bytes += range.count * a.meta.elem_size;
  outbox_[side].reserve(bytes, compute_.get());
  std::size_t at = 0;
  for (std::size_t f = 0; f < arrays_.size(); ++f) {
    const Array& a = arrays_[f];
    if (!in_set(a.meta, set) || range.count == 0) continue;
    const std::size_t b = range.count * a.meta.elem_size;
    check(cudaMemcpyAsync(outbox_[side].data() + at, a.data.get() + range.first * a.meta.elem_size, b, cudaMemcpyDeviceToDevice, compute_.get()),
          "stage");
    if (shift.axis >= 0 && a.meta.spec == &kParticleFields[kField_pos] && a.meta.component == shift.axis)
      launch(compute_.get(), range.count, shift_kernel, reinterpret_cast<float*>(outbox_[side].data() + at), u32(range.count), shift);
    at += b;
  }
  out_count_[side] = range.count;
  out_bytes_[side] = bytes;
  check(cudaEventRecord(staged_.get(), compute_.get()), "cudaEventRecord(staged)");
}

// The protocol is HaloExchange's (halo_exchange.cpp, tested on the CPU); these are its copies,
// all on the copy stream, so that the compute stream keeps running what was queued after the
// staging (the interior of the fluid loop) while the payload travels.
std::array<std::size_t, 2> DeviceSlabArrays::exchange(SlabTransport& t, FieldSet) {
  select();
  const std::array<Outgoing, 2> out{Outgoing{outbox_[kLeft].data(), out_count_[kLeft], out_bytes_[kLeft]},
                                    Outgoing{outbox_[kRight].data(), out_count_[kRight], out_bytes_[kRight]}};
  in_count_ = halo_.exchange(t, *this, out);
  return in_count_;
}

bool DeviceSlabArrays::peer_both_ways(int other) {
  if (!can_access_peer(device_, other) || !can_access_peer(other, device_)) return false;
  const cudaError_t e = cudaDeviceEnablePeerAccess(other, 0);
  if (e == cudaErrorPeerAccessAlreadyEnabled) (void)cudaGetLastError();
  else check(e, "cudaDeviceEnablePeerAccess");
  return true;
}
void DeviceSlabArrays::wait_staged() { check(cudaEventSynchronize(staged_.get()), "halo: outgoing buffers"); }
void DeviceSlabArrays::copy_to_host(void* host, const void* device, std::size_t bytes) {
  check(cudaMemcpyAsync(host, device, bytes, cudaMemcpyDeviceToHost, copy_.get()), "halo D2H");
}
void DeviceSlabArrays::copy_from_host(void* device, const void* host, std::size_t bytes) {
  check(cudaMemcpyAsync(device, host, bytes, cudaMemcpyHostToDevice, copy_.get()), "halo H2D");
}
void DeviceSlabArrays::copy_peer(void* device, const void* their_device, int their_device_index, std::size_t bytes) {
  check(cudaMemcpyPeerAsync(device, device_, their_device, their_device_index, bytes, copy_.get()), "cudaMemcpyPeerAsync");
}
void DeviceSlabArrays::after_incoming_read() { check(cudaStreamWaitEvent(copy_.get(), consumed_.get(), 0), "cudaStreamWaitEvent(consumed)"); }
// The copy stream waits for the readers of the incoming buffers (after_incoming_read) and holds
// their growth (incoming()): once it is idle, MPI may write them.
void DeviceSlabArrays::wait_incoming_read() { check(cudaStreamSynchronize(copy_.get()), "halo: incoming buffers read"); }
void DeviceSlabArrays::wait_copies() { check(cudaStreamSynchronize(copy_.get()), "halo copies"); }
// HaloExchange asks for the incoming buffers after after_incoming_read(): the copy stream already
// waits for the kernels that read the old blocks, so a block that must grow is freed and its
// successor allocated in the copy stream's order. Neither the host nor the compute stream (which
// may be running the interior of the fluid loop) waits.
void* DeviceSlabArrays::incoming(Side side, std::size_t bytes) {
  inbox_[side].reserve(bytes, copy_.get());
  return inbox_[side].data();
}
void* DeviceSlabArrays::pinned(int which, std::size_t bytes) {
  pinned_[which].reserve(bytes);
  return pinned_[which].data();
}

void DeviceSlabArrays::append_received(Side side, FieldSet set) {
  select();
  const std::size_t n = in_count_[side];
  if (n == 0) return;
  reserve(size_ + n);
  std::size_t at = 0;
  for (auto& a : arrays_) {
    if (!in_set(a.meta, set)) continue;
    const std::size_t b = n * a.meta.elem_size;
    check(cudaMemcpyAsync(a.data.get() + size_ * a.meta.elem_size, inbox_[side].data() + at, b, cudaMemcpyDeviceToDevice, compute_.get()), "append");
    at += b;
  }
  zero_fields_outside(set, size_, n);
  size_ += n;
  check(cudaEventRecord(consumed_.get(), compute_.get()), "cudaEventRecord(consumed)");
}

void DeviceSlabArrays::scatter_received(Side side) {
  select();
  const std::size_t n = in_count_[side];
  if (n != slot_count_[side]) throw std::runtime_error("halo refresh: count mismatch");
  std::size_t at = 0;
  for (auto& a : arrays_) {
    if (!in_set(a.meta, FieldSet::Refresh)) continue;
    launch(compute_.get(), n, scatter_kernel, reinterpret_cast<const float*>(inbox_[side].data() + at), slots_[side].as<const std::uint32_t>(),
           reinterpret_cast<float*>(a.data.get()), u32(n));
    at += n * a.meta.elem_size;
  }
  check(cudaEventRecord(consumed_.get(), compute_.get()), "cudaEventRecord(consumed)");
}

// ---- periodic images ----------------------------------------------------------------------------

void DeviceSlabArrays::forget_images() {
  images_ = {0, 0, 0};
  local_images_ = {0, 0, 0};
}

void DeviceSlabArrays::make_images(const CellGrid& geometry, int axis) {
  select();
  const std::size_t n = size_;  // images of the particles that exist before this axis
  if (n == 0) return;
  image_source_[axis].reserve(2 * n * sizeof(std::uint32_t), compute_.get());
  image_target_[axis].reserve(2 * n * sizeof(std::uint32_t), compute_.get());
  for (const bool local : {true, false}) {
    for (const int layer : {0, geometry.lattice().cells[axis] - 1}) append_images(geometry, axis, layer, local, n);
    if (local) local_images_[axis] = images_[axis];
  }
}

// Images of particles [0, n) in one cell layer, of owned columns (local) or halo columns: a flag
// per particle, an exclusive scan, a compaction (index order), then the Ghost fields gathered and
// shifted by one period to the end.
void DeviceSlabArrays::append_images(const CellGrid& geometry, int axis, int layer, bool local, std::size_t n) {
  const Lattice& L = geometry.lattice();
  std::uint32_t* flags = sort_values_[0].as<std::uint32_t>();
  std::uint32_t* prefix = sort_values_[1].as<std::uint32_t>();
  launch(compute_.get(), n, layer_flag_kernel, static_cast<const float*>(fields().pos[0]), static_cast<const float*>(fields().pos[axis]), L,
         axis, layer, geometry.owned_lo(), geometry.owned_hi(), local, flags, u32(n));
  std::uint32_t* list = image_source_[axis].as<std::uint32_t>() + images_[axis];
  const std::size_t count = scan_flags(flags, prefix, n);
  launch(compute_.get(), n, compact_kernel, static_cast<const std::uint32_t*>(flags), static_cast<const std::uint32_t*>(prefix), list, u32(n));
  reserve(size_ + count);
  gather_fields(FieldSet::Ghost, list, count, size_, periodic_shift(L, axis, layer == 0));
  zero_fields_outside(FieldSet::Ghost, size_, count);
  launch(compute_.get(), count, iota_kernel, image_target_[axis].as<std::uint32_t>() + images_[axis], u32(size_), u32(count));
  size_ += count;
  images_[axis] += count;
}

void DeviceSlabArrays::record_halo_slots(std::size_t left, std::size_t right) {
  select();
  const std::size_t n = size_ - owned_;
  if (sort_first_ != owned_ || sort_count_ != n) throw std::logic_error("DeviceSlabArrays: record_halo_slots must follow the ghost sort");
  const std::uint32_t* perm = sort_values_[sorted_values_].as<const std::uint32_t>();
  std::uint32_t* slot_of = sort_values_[1 - sorted_values_].as<std::uint32_t>();
  launch(compute_.get(), n, inverse_kernel, perm, slot_of, u32(owned_), u32(n));
  const std::size_t count[2] = {left, right}, from[2] = {0, left};
  for (Side side : {kLeft, kRight}) {
    slots_[side].reserve(count[side] * sizeof(std::uint32_t), compute_.get());
    if (count[side] > 0)
      check(cudaMemcpyAsync(slots_[side].data(), slot_of + from[side], count[side] * sizeof(std::uint32_t), cudaMemcpyDeviceToDevice, compute_.get()),
            "halo slots");
    slot_count_[side] = count[side];
  }
  for (int axis = 0; axis < 3; ++axis) {
    launch(compute_.get(), images_[axis], map_slots_kernel, image_source_[axis].as<std::uint32_t>(), static_cast<const std::uint32_t*>(slot_of),
           u32(owned_), u32(images_[axis]));
    launch(compute_.get(), images_[axis], map_slots_kernel, image_target_[axis].as<std::uint32_t>(), static_cast<const std::uint32_t*>(slot_of),
           u32(owned_), u32(images_[axis]));
  }
}

// Axis by axis in stream order: an image of an image copies after its source was refreshed.
void DeviceSlabArrays::refresh_images(ImagePart part) {
  select();
  for (int axis = 0; axis < 3; ++axis) {
    const std::size_t first = part == ImagePart::Local ? 0 : local_images_[axis];
    const std::size_t count = part == ImagePart::Local ? local_images_[axis] : images_[axis] - local_images_[axis];
    for (auto& a : arrays_)
      if (in_set(a.meta, FieldSet::Refresh))
        launch(compute_.get(), count, copy_within_kernel, reinterpret_cast<float*>(a.data.get()),
               image_source_[axis].as<const std::uint32_t>() + first, image_target_[axis].as<const std::uint32_t>() + first, u32(count));
  }
}

// ---- checks -------------------------------------------------------------------------------------

// A flag per particle and a scan give the count (one small read-back per step); only when some
// particle escaped, their ids come back and the others are kept by a sort on the flag.
std::vector<std::uint32_t> DeviceSlabArrays::remove_escaped(const OpenSides& open) {
  select();
  const std::size_t n = owned_;
  if (n == 0 || !open.open) return {};
  std::uint32_t* flags = sort_values_[0].as<std::uint32_t>();
  std::uint32_t* prefix = sort_values_[1].as<std::uint32_t>();
  launch(compute_.get(), n, escaped_flag_kernel, fields(), dim_, open, u32(n), flags);
  const std::size_t count = scan_flags(flags, prefix, n);
  if (count == 0) return {};
  // Their ids: indices by compaction, ids gathered, copied back.
  std::uint32_t* list = scratch_.as<std::uint32_t>();
  std::uint32_t* ids = sort_keys_[0].as<std::uint32_t>();
  launch(compute_.get(), n, compact_kernel, static_cast<const std::uint32_t*>(flags), static_cast<const std::uint32_t*>(prefix), list, u32(n));
  launch(compute_.get(), count, gather_kernel<std::uint32_t>, static_cast<const std::uint32_t*>(fields().id),
         static_cast<const std::uint32_t*>(list), ids, u32(count));
  result_host_.reserve(count * sizeof(std::uint32_t));
  check(cudaMemcpyAsync(result_host_.data(), ids, count * sizeof(std::uint32_t), cudaMemcpyDeviceToHost, compute_.get()), "escaped ids");
  check(cudaStreamSynchronize(compute_.get()), "escaped ids");
  std::vector<std::uint32_t> out(count);
  std::memcpy(out.data(), result_host_.data(), count * sizeof(std::uint32_t));
  std::sort(out.begin(), out.end());
  // The flag as the sort key: the particles kept come first (by id), the escaped last, cut off.
  check(cudaMemcpyAsync(keys(), flags, n * sizeof(std::uint32_t), cudaMemcpyDeviceToDevice, compute_.get()), "escaped keys");
  key_count_ = 2;
  sort_by_key(0, n);
  truncate(n - count);
  return out;
}

std::uint32_t DeviceSlabArrays::wrap_and_find_position_fault(const Lattice& L) {
  select();
  launch(compute_.get(), owned_, position_fault_kernel, fields(), L, u32(owned_), scratch_.as<std::uint32_t>());
  return min_u32(scratch_.as<const std::uint32_t>(), owned_);
}

std::uint32_t DeviceSlabArrays::find_unhealthy(const HealthLimits& limits) {
  select();
  launch(compute_.get(), owned_, health_kernel, fields(), dim_, limits, u32(owned_), scratch_.as<std::uint32_t>());
  return min_u32(scratch_.as<const std::uint32_t>(), owned_);
}

std::unique_ptr<SlabArrays> make_device_arrays(int device, int dim) { return std::make_unique<DeviceSlabArrays>(device, dim); }

}  // namespace spate::gpu
