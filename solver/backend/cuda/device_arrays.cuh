#pragma once
// A slab's particles in device memory, resident for the whole run, and the SlabArrays primitives
// over them: CUB radix sort, scans and reductions, a handful of copy kernels, and halo payloads
// moved by peer copies or through pinned host memory. What to move is decided by the shared host
// orchestration (domain/slab_topology.cpp), which the CPU tests run on HostSlabArrays. Shared by
// the two CUDA translation units: device_arrays.cu (these primitives) and cuda_kernels.cu (the
// physics loops).
#include <cuda_runtime.h>

#include <array>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

#include "../../domain/slab_arrays.hpp"
#include "device_plan.hpp"
#include "halo_exchange.hpp"

namespace spate::gpu {

void check(cudaError_t e, const char* what);

// The device arrays of one slab, by value into every kernel: one pointer per component of every
// registry field (field_registry.hpp), e.g. float* pos[3], float* density, std::uint8_t* material.
// Components beyond dim are null.
template <class T, FieldShape S>
struct DevicePointers {
  using type = T*;
};
template <class T>
struct DevicePointers<T, FieldShape::Vector> {
  using type = T* [3];
};
struct DeviceFields {
#define SPATE_DEVICE_MEMBER(member, ctype, shape, ...) typename DevicePointers<ctype, FieldShape::shape>::type member;
  SPATE_PARTICLE_FIELDS(SPATE_DEVICE_MEMBER)
#undef SPATE_DEVICE_MEMBER
};

// Host and device layouts agree field by field: the same element type and the same number of
// component arrays (both are generated from the registry; this catches a hand edit of either).
template <class Host>
struct HostLayout {
  using element = typename Host::value_type;
  static constexpr int arrays = 1;
};
template <class Host>
struct HostLayout<Host[3]> {
  using element = typename Host::value_type;
  static constexpr int arrays = 3;
};
template <class Device>
struct DeviceLayout {
  using element = std::remove_pointer_t<Device>;
  static constexpr int arrays = 1;
};
template <class Device>
struct DeviceLayout<Device[3]> {
  using element = std::remove_pointer_t<Device>;
  static constexpr int arrays = 3;
};
#define SPATE_SAME_LAYOUT(member, ...)                                                                                      \
  static_assert(std::is_same_v<HostLayout<decltype(ParticleStore::member)>::element,                                      \
                               DeviceLayout<decltype(DeviceFields::member)>::element> &&                                  \
                    HostLayout<decltype(ParticleStore::member)>::arrays == DeviceLayout<decltype(DeviceFields::member)>::arrays, \
                "host and device layouts of field '" #member "' differ");
SPATE_PARTICLE_FIELDS(SPATE_SAME_LAYOUT)
#undef SPATE_SAME_LAYOUT

// Owning handles: whatever a DeviceSlabArrays holds is released when it goes, also when its
// constructor or a growth throws halfway.
struct DeviceFree {
  void operator()(char* p) const noexcept { cudaFree(p); }
};
struct StreamOrderedFree {  // cudaMallocAsync memory, freed in the order of `stream`
  cudaStream_t stream = nullptr;
  void operator()(char* p) const noexcept { cudaFreeAsync(p, stream); }
};
struct PinnedFree {
  void operator()(char* p) const noexcept { cudaFreeHost(p); }
};
struct StreamDestroy {
  void operator()(cudaStream_t s) const noexcept { cudaStreamDestroy(s); }
};
struct EventDestroy {
  void operator()(cudaEvent_t e) const noexcept { cudaEventDestroy(e); }
};
using DeviceMemory = std::unique_ptr<char, DeviceFree>;
using StreamOrderedMemory = std::unique_ptr<char, StreamOrderedFree>;
using PinnedMemory = std::unique_ptr<char, PinnedFree>;
using Stream = std::unique_ptr<std::remove_pointer_t<cudaStream_t>, StreamDestroy>;
using Event = std::unique_ptr<std::remove_pointer_t<cudaEvent_t>, EventDestroy>;

// Device memory that grows (with headroom, never shrinking); growing discards the contents and
// first waits for `in_use`, the stream whose work may still read the old block.
struct DeviceBuffer : Growable<DeviceMemory> {
  void reserve(std::size_t n, cudaStream_t in_use);
  template <class T>
  T* as() const {
    return reinterpret_cast<T*>(data());
  }
};

// The same, allocated and freed in the order of one stream (cudaMallocAsync/cudaFreeAsync):
// growing neither waits for the host nor, as cudaMalloc and cudaFree do, for every stream of the
// device. For the incoming halo buffers, which grow on the copy stream while the compute stream
// may be running the interior of the fluid loop.
struct StreamOrderedBuffer : Growable<StreamOrderedMemory> {
  void reserve(std::size_t n, cudaStream_t stream);
};

// Page-locked host memory (fast, asynchronous copies) that grows the same way.
struct PinnedBuffer : Growable<PinnedMemory> {
  void reserve(std::size_t n);
};

// The primitives (SlabArrays) and, for the halo protocol (HaloExchange), the copies it queues.
class DeviceSlabArrays final : public SlabArrays, private DeviceCopies {
 public:
  DeviceSlabArrays(int device, int dim);
  ~DeviceSlabArrays() override;
  DeviceSlabArrays(const DeviceSlabArrays&) = delete;
  DeviceSlabArrays& operator=(const DeviceSlabArrays&) = delete;

  std::size_t size() const override { return size_; }
  std::size_t owned() const override { return owned_; }
  void upload(const ParticleStore& host) override;
  void download(ParticleStore& host, CellGrid& grid) override;
  void truncate(std::size_t n) override;
  void set_owned(std::size_t n) override { owned_ = n; }
  void set_id_bound(std::uint32_t bound) override;
  void set_migration_hops(const std::vector<std::int8_t>& hops) override;
  void compute_keys(const CellGrid& geometry, std::size_t first, std::size_t last, bool migrating) override;
  void sort_by_key(std::size_t first, std::size_t last) override;
  void build_table(const CellGrid& geometry) override;
  std::vector<std::uint32_t> table_entries(const TableRead& read) override;
  void stage(Side side, FieldSet set, ParticleRange range, Shift shift) override;
  std::array<std::size_t, 2> exchange(SlabTransport& t, FieldSet set) override;
  void append_received(Side side, FieldSet set) override;
  void scatter_received(Side side) override;
  void forget_images() override;
  void make_images(const CellGrid& geometry, int axis) override;
  void record_halo_slots(std::size_t left, std::size_t right) override;
  void refresh_images(ImagePart part) override;
  std::vector<std::uint32_t> remove_escaped(const OpenSides& open) override;
  std::uint32_t wrap_and_find_position_fault(const Lattice& L) override;
  std::uint32_t find_unhealthy(const HealthLimits& limits) override;

  // For the physics loops (cuda_kernels.cu), all on the compute stream.
  void select() const;
  DeviceFields fields() const;
  const CellGridView& view() const { return view_; }  // start points at the device cell table
  const Lattice& lattice() const { return lattice_; }
  int dim() const { return dim_; }
  cudaStream_t stream() const { return compute_.get(); }
  void swap_rates();                   // ParticleStore::swap_rates, on the pointers
  float* scratch() const { return scratch_.as<float>(); }  // one word per slot
  // The minimum of n words of `in` (CUB, exact), copied to the host.
  std::uint32_t min_u32(const std::uint32_t* in, std::size_t n);
  float min_f32(const float* in, std::size_t n);
  std::size_t bytes() const;           // device memory held

 private:
  struct Array {
    FieldRef meta;  // registry entry, component, element size (data unused)
    DeviceMemory data;
  };
  // The array of component `component` of registry field `field`.
  int index_of(int field, int component) const;
  void reserve(std::size_t n);  // particle slots, keeping [0, size_)
  void* cub_scratch(std::size_t bytes);
  std::size_t scan_flags(const std::uint32_t* flags, std::uint32_t* prefix, std::size_t n);
  // DeviceCopies, for HaloExchange: cudaMemcpy*Async on the copy stream.
  int device() const override { return device_; }
  bool peer_both_ways(int other) override;
  void wait_staged() override;
  void copy_to_host(void* host, const void* device, std::size_t bytes) override;
  void copy_from_host(void* device, const void* host, std::size_t bytes) override;
  void copy_peer(void* device, const void* their_device, int their_device_index, std::size_t bytes) override;
  void after_incoming_read() override;
  void wait_incoming_read() override;
  void wait_copies() override;
  void* incoming(Side side, std::size_t bytes) override;
  void* pinned(int which, std::size_t bytes) override;
  void append_images(const CellGrid& geometry, int axis, int layer, bool local, std::size_t n);
  // Zeroes the fields outside `set` of particles [first, first + count) (appended with `set`
  // only: the host twin's new particles start at zero, and nothing uninitialised is ever read,
  // e.g. by the gather of the next sort).
  void zero_fields_outside(FieldSet set, std::size_t first, std::size_t count);
  std::uint32_t* result() const { return reinterpret_cast<std::uint32_t*>(result_.get()); }
  std::uint32_t* keys() const { return reinterpret_cast<std::uint32_t*>(keys_.get()); }
  void gather_fields(FieldSet set, const std::uint32_t* from, std::size_t count, std::size_t to, Shift shift);

  int device_, dim_;
  // Declared before the memory, so destroyed after it: a stream-ordered block is freed on its stream.
  Stream compute_, copy_;
  Event staged_;    // the outgoing buffers are complete
  Event consumed_;  // the incoming buffers were read (append, scatter)
  std::vector<Array> arrays_;  // ParticleStore(dim).fields(), in that order
  std::size_t capacity_ = 0, size_ = 0, owned_ = 0;

  DeviceMemory keys_;  // one per slot, kept on growth like the fields
  DeviceBuffer sort_keys_[2], sort_values_[2], scratch_, cub_;
  int sorted_values_ = 0;             // which sort_values_ holds the last sort's permutation
  std::size_t sort_first_ = 0, sort_count_ = 0;
  std::uint32_t key_count_ = 0, id_bound_ = 0xffffffffu;
  DeviceBuffer table_, hops_;
  std::size_t table_entries_ = 0;
  CellGridView view_{};
  Lattice lattice_{};

  HaloExchange halo_;
  std::array<DeviceBuffer, 2> outbox_;
  std::array<StreamOrderedBuffer, 2> inbox_;  // grown on the copy stream (incoming())
  std::array<PinnedBuffer, 4> pinned_;  // outgoing left/right, incoming left/right
  std::array<std::size_t, 2> out_count_{0, 0}, out_bytes_{0, 0}, in_count_{0, 0};
  std::array<DeviceBuffer, 2> slots_;
  std::array<std::size_t, 2> slot_count_{0, 0};
  // Periodic images per axis: source and target slots, the local part [0, local) first, then
  // the halo part [local, total).
  std::array<DeviceBuffer, 3> image_source_, image_target_;
  std::array<std::size_t, 3> images_{0, 0, 0}, local_images_{0, 0, 0};
  PinnedBuffer mirror_;               // the host mirror's staging (output steps)
  DeviceMemory result_;               // device words for reductions and counts
  PinnedBuffer result_host_;
};

}  // namespace spate::gpu
