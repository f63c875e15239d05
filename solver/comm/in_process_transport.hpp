#pragma once
// Slabs that live in one process as worker threads: buffers are copied with memcpy through a shared
// hub, collectives combine per-slab slots behind a barrier. A worker that fails calls
// `abandon()`: the others see PeerFailure at their next collective instead of waiting forever.
#include <atomic>
#include <barrier>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "transport.hpp"

namespace spate {

class InProcessHub final : public LocalSlabs {
 public:
  explicit InProcessHub(int slabs);
  int slabs() const { return slabs_; }
  int local_slabs() const override { return slabs_; }
  int first_slab() const override { return 0; }
  int slab_count() const override { return slabs_; }
  std::unique_ptr<SlabTransport> endpoint(int slab, bool periodic_x) override;
  void abandon() override;  // called by a failing worker, once
  bool failed() const { return failed_.load(); }

 private:
  friend class InProcessTransport;
  void wait();

  int slabs_;
  std::barrier<> barrier_;
  std::atomic<bool> failed_{false};
  std::vector<Bytes> to_left_, to_right_;
  std::vector<double> dslot_;
  std::vector<std::int64_t> islot_;
  std::vector<std::vector<std::int64_t>> vslot_;
  std::vector<Bytes> gslot_;
  // post()/collect(): per slab, two mailboxes used alternately (post k writes mailbox k % 2 only
  // once both neighbours collected post k - 2) and the number of posts and collects so far.
  struct Mailbox {
    Bytes to_left, to_right;
  };
  std::mutex post_mutex_;
  std::condition_variable post_cv_;
  std::vector<Mailbox> mailbox_[2];
  std::vector<std::uint64_t> posts_, collects_;
};

}  // namespace spate
