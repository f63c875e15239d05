#pragma once
// How slabs talk: neighbour exchange of byte buffers and global reductions. `solver/domain` decides
// what to send; a transport only moves bytes. The in-process transport (threads sharing memory) and
// the MPI transport implement this one interface, so a run can be R ranks x D devices.
//
// Slabs are numbered globally left to right along x; slab s has neighbours s-1 and s+1 (wrapping
// around when x is periodic, possibly to itself).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

namespace spate {

using Bytes = std::vector<char>;

class SlabTransport {
 public:
  virtual ~SlabTransport() = default;
  virtual int slab() const = 0;
  virtual int slab_count() const = 0;

  // Send to_left to slab left_of(slab()) and to_right to right_of(slab()); receive what they sent
  // this way. A slab without a neighbour on a side receives an empty buffer from it.
  virtual void exchange(const Bytes& to_left, const Bytes& to_right, Bytes& from_left,
                        Bytes& from_right) = 0;

  // The same exchange in two halves, so that a slab can work in between: post() hands the buffers
  // over and returns without waiting for the neighbours; collect() waits until both neighbours
  // have posted theirs and returns them. A slab that is early therefore waits only for its
  // neighbours to post, not for them to reach collect(). Every slab calls post() then collect(),
  // in the same order relative to its other calls. By default both halves happen in collect().
  virtual void post(Bytes to_left, Bytes to_right) {
    posted_left_ = std::move(to_left);
    posted_right_ = std::move(to_right);
  }
  virtual void collect(Bytes& from_left, Bytes& from_right) {
    exchange(posted_left_, posted_right_, from_left, from_right);
  }

  // Collectives over every slab. Each is exact and independent of the number of slabs:
  // minimum/maximum are order-free, integer sums are exact.
  virtual double min(double v) = 0;
  virtual double max(double v) = 0;
  virtual std::int64_t sum(std::int64_t v) = 0;
  // Element-wise integer sum of equal-length vectors.
  virtual void sum(std::vector<std::int64_t>& v) = 0;
  // Every slab's buffer, in slab order, on every slab.
  virtual std::vector<Bytes> allgather(const Bytes& mine) = 0;
  // Every slab's value of a plain type (its bytes), in slab order, on every slab.
  template <class T>
  std::vector<T> allgather_value(const T& mine) {
    static_assert(std::is_trivially_copyable_v<T>, "allgather_value sends a value's bytes");
    Bytes b(sizeof mine);
    std::memcpy(b.data(), &mine, sizeof mine);
    std::vector<T> all;
    for (const Bytes& part : allgather(b)) {
      T v{};
      std::memcpy(&v, part.data(), std::min(sizeof v, part.size()));
      all.push_back(v);
    }
    return all;
  }
  // Every slab's buffer, in slab order, on slab 0 only (the others get an empty list). For the big
  // gathers (checkpoints): only the writer holds everything, and `mine` is moved, not copied.
  virtual std::vector<Bytes> gather(Bytes mine) = 0;
  virtual void barrier() = 0;
  // Any slab may raise a failure; every slab learns of it at the next call to this (no hang).
  virtual bool any(bool flag) = 0;

  // Whether slab `s` runs in this process (its device memory can be reached by peer copies).
  virtual bool shares_memory_with(int s) const {
    (void)s;
    return true;
  }

  // CUDA-aware MPI (build option SPATE_CUDA_AWARE_MPI): moves device buffers to and from the
  // neighbours on other ranks, the device pointers handed straight to MPI; the byte counts are
  // known to both ends from an exchange() before. A side whose neighbour shares this process's
  // memory is left alone. Collective like exchange(); returns false where unsupported.
  struct DeviceSpan {
    const void* send = nullptr;
    std::size_t send_bytes = 0;
    void* recv = nullptr;
    std::size_t recv_bytes = 0;
  };
  virtual bool exchange_device(const DeviceSpan& left, const DeviceSpan& right) {
    (void)left, (void)right;
    return false;
  }

  bool periodic_x = false;
  int left_of(int s) const { return s > 0 ? s - 1 : (periodic_x ? slab_count() - 1 : -1); }
  int right_of(int s) const { return s + 1 < slab_count() ? s + 1 : (periodic_x ? 0 : -1); }

 private:
  Bytes posted_left_, posted_right_;  // the default post()
};

// Raised in a slab's collective when another slab of this process gave up.
struct PeerFailure : std::runtime_error {
  PeerFailure() : std::runtime_error("another slab failed") {}
};

// The slabs that run in this process, one worker thread each: local slab d is global slab
// first_slab() + d. Implemented by the in-process hub (every slab here) and the MPI node (this
// rank's share of R x D slabs).
class LocalSlabs {
 public:
  virtual ~LocalSlabs() = default;
  virtual int local_slabs() const = 0;
  virtual int first_slab() const = 0;
  virtual int slab_count() const = 0;
  virtual std::unique_ptr<SlabTransport> endpoint(int local, bool periodic_x) = 0;
  // Called once by a worker that leaves early (failure): the others see PeerFailure at their next
  // collective instead of waiting forever.
  virtual void abandon() = 0;
};

}  // namespace spate
