#pragma once
// How a slab's halo and migration payload reaches its neighbours' device memory: the protocol of
// DeviceSlabArrays::exchange, in plain C++ so that the CPU tests run it (over an InProcessHub,
// with host memory standing in for the devices). The CUDA side only implements DeviceCopies with
// cudaMemcpy*Async calls on its copy stream (device_arrays.cu).
//
// Pull model: each slab stages what it sends into its own outgoing device buffer; a small header
// (count, bytes, device, address of the outgoing buffer) goes to each neighbour through the host
// transport; each slab then copies its neighbours' outgoing buffers into its own incoming ones,
// by peer copy where both devices reach each other, or from the payload that rode along with the
// header through pinned host memory; a closing empty exchange tells every slab that nobody reads
// its outgoing buffers any more.
#include <array>
#include <cstddef>
#include <cstdint>

#include "../../comm/transport.hpp"
#include "../../domain/slab_plan.hpp"

namespace spate::gpu {

enum class HaloLink { None, Peer, Staged, DeviceMpi };

// The link of one neighbour pair, the same at both ends: peer when both slabs run in this process
// and each device reaches the other (or they share a device); otherwise staged through host
// memory, or device-to-device through CUDA-aware MPI when the build asks for it. `force_staged`
// stages the pairs of one process too (SPATE_CUDA_HALO_LINK=staged: the staged path on one GPU).
HaloLink choose_halo_link(bool has_neighbour, bool shares_memory, int mine, int theirs, bool peer_both_ways,
                          bool cuda_aware_mpi, bool force_staged = false);

// SPATE_CUDA_HALO_LINK: unset, empty or "auto" chooses as above, "staged" forces staged links
// inside the process (to exercise that path where every link would be a same-device or peer
// copy). Anything else: std::invalid_argument naming the variable.
bool staged_links_forced(const char* env);

// The device side of an exchange. Copies are queued (asynchronous) until wait_copies().
class DeviceCopies {
 public:
  virtual ~DeviceCopies() = default;
  virtual int device() const = 0;
  // Whether this device and `other` reach each other's memory; enables the access if so.
  virtual bool peer_both_ways(int other) = 0;
  virtual void wait_staged() = 0;  // the host waits until the outgoing buffers are complete
  virtual void copy_to_host(void* host, const void* device, std::size_t bytes) = 0;
  virtual void copy_from_host(void* device, const void* host, std::size_t bytes) = 0;
  virtual void copy_peer(void* device, const void* their_device, int their_device_index, std::size_t bytes) = 0;
  // Queued incoming copies start only after the previous incoming buffers were read;
  // wait_incoming_read makes the host wait for that (before MPI writes them).
  virtual void after_incoming_read() = 0;
  virtual void wait_incoming_read() = 0;
  virtual void wait_copies() = 0;
  // The incoming device buffer of a side, at least `bytes` long (may reallocate).
  virtual void* incoming(Side side, std::size_t bytes) = 0;
  // Page-locked host staging: 0/1 outgoing left/right, 2/3 incoming left/right.
  virtual void* pinned(int which, std::size_t bytes) = 0;
};

// Payload bytes received so far by every HaloExchange of this process, by link (a test or a check
// can see which path the halos took).
struct HaloTraffic {
  std::uint64_t peer_bytes = 0, staged_bytes = 0, device_mpi_bytes = 0;
};
HaloTraffic halo_traffic();

struct Outgoing {
  const void* device = nullptr;  // the staged fields, one block per field
  std::size_t count = 0, bytes = 0;
};

class HaloExchange {
 public:
  explicit HaloExchange(bool cuda_aware_mpi = false, bool force_staged = false)
      : cuda_aware_mpi_(cuda_aware_mpi), force_staged_(force_staged) {}
  // Collective with both neighbours. Returns the particle counts received from left and right,
  // in copies.incoming(side, ...).
  std::array<std::size_t, 2> exchange(SlabTransport& t, DeviceCopies& copies, const std::array<Outgoing, 2>& out);
  const std::array<HaloLink, 2>& links() const { return links_; }

 private:
  void discover(SlabTransport& t, DeviceCopies& copies);
  bool cuda_aware_mpi_, force_staged_;
  bool known_ = false;
  std::array<HaloLink, 2> links_{HaloLink::None, HaloLink::None};
};

}  // namespace spate::gpu
