// The MPI transport. The D workers of one rank share an MpiNode: a neighbour on the same rank is
// served by memcpy exactly as in the in-process hub; a neighbour on another rank, and the rank-level
// part of every collective, go through MPI.
//
// Threads: every MPI call is made by the rank's first worker (local device 0) while the other
// workers of the rank wait at a node barrier, so MPI sees one thread at a time
// (MPI_THREAD_SERIALIZED; in practice the main thread). This costs one node barrier more per
// exchange than letting the two edge workers talk to MPI concurrently, and needs no
// MPI_THREAD_MULTIPLE, which many MPI builds make slow or leave out.
//
// Determinism: collectives reduce the local slots in slab order, then across ranks with exact
// operations only (min, max, integer sums); allgather concatenates in global slab order. Results
// are therefore the same bits for any R x D split.
#include "mpi_transport.hpp"

#include <mpi.h>

#include <algorithm>
#include <atomic>
#include <barrier>
#include <climits>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace spate {

namespace {

// Tags name the direction a message travels, so that with two ranks and periodic x (left and right
// neighbour are the same rank) the two messages cannot be confused.
constexpr int kTagLeftward = 11;
constexpr int kTagRightward = 12;
constexpr int kTagGather = 13;
constexpr int kTagPostLeftward = 14;  // post()/collect()
constexpr int kTagPostRightward = 15;
constexpr int kTagDeviceLeftward = 21;  // exchange_device (CUDA-aware MPI)
constexpr int kTagDeviceRightward = 22;
constexpr std::int64_t kChunk = std::int64_t{1} << 30;  // broadcast pieces stay below INT_MAX bytes

int byte_count(const Bytes& b) {
  if (b.size() > static_cast<std::size_t>(INT_MAX))
    throw std::runtime_error("MPI transport: a neighbour message of " + std::to_string(b.size()) + " bytes exceeds 2 GiB");
  return static_cast<int>(b.size());
}

class MpiNode final : public LocalSlabs {
 public:
  explicit MpiNode(int local)
      : local_(local), barrier_(local), to_left_(local), to_right_(local), dev_left_(local), dev_right_(local), dslot_(local), islot_(local), vslot_(local), gslot_(local) {
    MPI_Comm_dup(MPI_COMM_WORLD, &comm_);
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &ranks_);
    int lo = local, hi = local;
    MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_INT, MPI_MIN, comm_);
    MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_INT, MPI_MAX, comm_);
    if (lo != hi)
      throw std::runtime_error("MPI transport: ranks were started with different --devices (" + std::to_string(lo) + " to " +
                               std::to_string(hi) + ")");
  }
  ~MpiNode() override {
    // After a failure a peer may never reach the matching free; MPI_Abort cleans up instead.
    if (!failed_) MPI_Comm_free(&comm_);
  }
  int local_slabs() const override { return local_; }
  int first_slab() const override { return rank_ * local_; }
  int slab_count() const override { return ranks_ * local_; }
  std::unique_ptr<SlabTransport> endpoint(int local, bool periodic_x) override;
  void abandon() override {
    failed_ = true;
    barrier_.arrive_and_drop();
  }

 private:
  friend class MpiTransport;

  void wait() {
    if (failed_) throw PeerFailure();
    barrier_.arrive_and_wait();
    if (failed_) throw PeerFailure();
  }
  bool is_local(int slab) const { return slab / local_ == rank_; }
  int rank_of(int slab) const { return slab / local_; }

  // Leader only: the edge slabs' messages to and from the neighbouring ranks.
  void exchange_across_ranks(int left_slab, int right_slab) {
    MPI_Request sends[2];
    int n = 0;
    const bool left = left_slab >= 0 && !is_local(left_slab);
    const bool right = right_slab >= 0 && !is_local(right_slab);
    if (left) MPI_Isend(to_left_[0].data(), byte_count(to_left_[0]), MPI_BYTE, rank_of(left_slab), kTagLeftward, comm_, &sends[n++]);
    if (right)
      MPI_Isend(to_right_[local_ - 1].data(), byte_count(to_right_[local_ - 1]), MPI_BYTE, rank_of(right_slab), kTagRightward, comm_,
                &sends[n++]);
    if (left) receive(rank_of(left_slab), kTagRightward, from_left_rank_);
    if (right) receive(rank_of(right_slab), kTagLeftward, from_right_rank_);
    MPI_Waitall(n, sends, MPI_STATUSES_IGNORE);
  }

  // Leader only, CUDA-aware MPI: the edge slabs' device buffers to and from the neighbouring ranks.
  void exchange_device_across_ranks(int left_slab, int right_slab) {
    MPI_Request requests[4];
    int n = 0;
    const SlabTransport::DeviceSpan& l = dev_left_[0];
    const SlabTransport::DeviceSpan& r = dev_right_[local_ - 1];
    auto count = [](std::size_t bytes) {
      if (bytes > static_cast<std::size_t>(INT_MAX)) throw std::runtime_error("MPI transport: a device halo message exceeds 2 GiB");
      return static_cast<int>(bytes);
    };
    if (left_slab >= 0 && !is_local(left_slab)) {
      MPI_Irecv(l.recv, count(l.recv_bytes), MPI_BYTE, rank_of(left_slab), kTagDeviceRightward, comm_, &requests[n++]);
      MPI_Isend(l.send, count(l.send_bytes), MPI_BYTE, rank_of(left_slab), kTagDeviceLeftward, comm_, &requests[n++]);
    }
    if (right_slab >= 0 && !is_local(right_slab)) {
      MPI_Irecv(r.recv, count(r.recv_bytes), MPI_BYTE, rank_of(right_slab), kTagDeviceLeftward, comm_, &requests[n++]);
      MPI_Isend(r.send, count(r.send_bytes), MPI_BYTE, rank_of(right_slab), kTagDeviceRightward, comm_, &requests[n++]);
    }
    MPI_Waitall(n, requests, MPI_STATUSES_IGNORE);
  }

  void receive(int source, int tag, Bytes& out) {
    MPI_Status status;
    MPI_Probe(source, tag, comm_, &status);
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    out.resize(static_cast<std::size_t>(count));
    MPI_Recv(out.data(), count, MPI_BYTE, source, tag, comm_, MPI_STATUS_IGNORE);
  }

  // Leader only: every slab's buffer in global slab order.
  void allgather_across_ranks() {
    std::vector<std::int64_t> sizes(static_cast<std::size_t>(ranks_) * local_);
    std::vector<std::int64_t> mine(local_);
    for (int d = 0; d < local_; ++d) mine[d] = static_cast<std::int64_t>(gslot_[d].size());
    MPI_Allgather(mine.data(), local_, MPI_INT64_T, sizes.data(), local_, MPI_INT64_T, comm_);
    gathered_.assign(sizes.size(), Bytes{});
    for (int r = 0; r < ranks_; ++r) {
      std::int64_t total = 0;
      for (int d = 0; d < local_; ++d) total += sizes[r * local_ + d];
      Bytes payload;
      if (r == rank_) {
        payload.reserve(static_cast<std::size_t>(total));
        for (auto& b : gslot_) payload.insert(payload.end(), b.begin(), b.end());
      } else {
        payload.resize(static_cast<std::size_t>(total));
      }
      for (std::int64_t at = 0; at < total; at += kChunk)
        MPI_Bcast(payload.data() + at, static_cast<int>(std::min(kChunk, total - at)), MPI_BYTE, r, comm_);
      std::int64_t at = 0;
      for (int d = 0; d < local_; ++d) {
        const std::int64_t n = sizes[r * local_ + d];
        gathered_[r * local_ + d].assign(payload.begin() + at, payload.begin() + at + n);
        at += n;
      }
    }
  }

  // Leader only: every slab's buffer to rank 0 (into gathered_ there, in global slab order); the
  // other ranks send theirs and free their slots. Rank 0 receives rank by rank, so the senders
  // only ever block on it.
  void gather_to_rank0() {
    std::vector<std::int64_t> sizes(static_cast<std::size_t>(ranks_) * local_);
    std::vector<std::int64_t> mine(local_);
    for (int d = 0; d < local_; ++d) mine[d] = static_cast<std::int64_t>(gslot_[d].size());
    MPI_Gather(mine.data(), local_, MPI_INT64_T, sizes.data(), local_, MPI_INT64_T, 0, comm_);
    gathered_.clear();
    if (rank_ != 0) {
      for (auto& b : gslot_) {
        const auto total = static_cast<std::int64_t>(b.size());
        for (std::int64_t at = 0; at < total; at += kChunk)
          MPI_Send(b.data() + at, static_cast<int>(std::min(kChunk, total - at)), MPI_BYTE, 0, kTagGather, comm_);
        Bytes().swap(b);
      }
      return;
    }
    gathered_.resize(sizes.size());
    for (int d = 0; d < local_; ++d) gathered_[d] = std::move(gslot_[d]);
    for (int r = 1; r < ranks_; ++r) {
      for (int d = 0; d < local_; ++d) {
        Bytes& b = gathered_[r * local_ + d];
        const std::int64_t total = sizes[r * local_ + d];
        b.resize(static_cast<std::size_t>(total));
        for (std::int64_t at = 0; at < total; at += kChunk)
          MPI_Recv(b.data() + at, static_cast<int>(std::min(kChunk, total - at)), MPI_BYTE, r, kTagGather, comm_, MPI_STATUS_IGNORE);
      }
    }
    gslot_.assign(local_, Bytes{});
  }

  int local_;
  int rank_ = 0, ranks_ = 1;
  MPI_Comm comm_ = MPI_COMM_NULL;
  std::barrier<> barrier_;
  std::atomic<bool> failed_{false};
  // Inputs, one slot per local slab; results written by the leader between the two barriers of a
  // collective and read after the second (rewritten only after the first barrier of a later one,
  // which every reader must have passed).
  std::vector<Bytes> to_left_, to_right_;
  std::vector<SlabTransport::DeviceSpan> dev_left_, dev_right_;
  Bytes from_left_rank_, from_right_rank_;
  std::vector<double> dslot_;
  std::vector<std::int64_t> islot_;
  std::vector<std::vector<std::int64_t>> vslot_;
  std::vector<Bytes> gslot_;
  double dresult_ = 0.0;
  std::int64_t iresult_ = 0;
  std::vector<std::int64_t> vresult_;
  std::vector<Bytes> gathered_;
};

class MpiTransport final : public SlabTransport {
 public:
  MpiTransport(MpiNode& node, int local) : node_(node), local_(local), slab_(node.first_slab() + local) {}
  int slab() const override { return slab_; }
  int slab_count() const override { return node_.slab_count(); }
  bool shares_memory_with(int s) const override { return node_.is_local(s); }

  void exchange(const Bytes& to_left, const Bytes& to_right, Bytes& from_left, Bytes& from_right) override {
    node_.to_left_[local_] = to_left;
    node_.to_right_[local_] = to_right;
    node_.wait();
    if (leader()) node_.exchange_across_ranks(left_of(node_.first_slab()), right_of(node_.first_slab() + node_.local_ - 1));
    node_.wait();
    const int l = left_of(slab_), r = right_of(slab_);
    const int first = node_.first_slab();
    from_left = l < 0 ? Bytes{} : node_.is_local(l) ? node_.to_right_[l - first] : node_.from_left_rank_;
    from_right = r < 0 ? Bytes{} : node_.is_local(r) ? node_.to_left_[r - first] : node_.from_right_rank_;
    // The slots are rewritten by the next exchange; nobody may start it before all have read.
    node_.wait();
  }
  // With one slab per rank, post() starts the sends to the neighbouring ranks and collect() waits
  // for theirs: a rank that is early waits only for its neighbours to post. With several slabs per
  // rank the in-node workers would have to meet anyway, so both halves happen in collect().
  void post(Bytes to_left, Bytes to_right) override {
    if (node_.local_ > 1) return SlabTransport::post(std::move(to_left), std::move(to_right));
    post_left_ = std::move(to_left);
    post_right_ = std::move(to_right);
    const int l = left_of(slab_), r = right_of(slab_);
    posted_ = 0;
    if (l >= 0 && l != slab_)
      MPI_Isend(post_left_.data(), byte_count(post_left_), MPI_BYTE, node_.rank_of(l), kTagPostLeftward, node_.comm_, &sends_[posted_++]);
    if (r >= 0 && r != slab_)
      MPI_Isend(post_right_.data(), byte_count(post_right_), MPI_BYTE, node_.rank_of(r), kTagPostRightward, node_.comm_, &sends_[posted_++]);
  }
  void collect(Bytes& from_left, Bytes& from_right) override {
    if (node_.local_ > 1) return SlabTransport::collect(from_left, from_right);
    const int l = left_of(slab_), r = right_of(slab_);
    // A slab that is its own neighbour (one slab, periodic x) receives what it sent the other way.
    from_left = l < 0 ? Bytes{} : l == slab_ ? post_right_ : Bytes{};
    from_right = r < 0 ? Bytes{} : r == slab_ ? post_left_ : Bytes{};
    if (l >= 0 && l != slab_) node_.receive(node_.rank_of(l), kTagPostRightward, from_left);
    if (r >= 0 && r != slab_) node_.receive(node_.rank_of(r), kTagPostLeftward, from_right);
    MPI_Waitall(posted_, sends_, MPI_STATUSES_IGNORE);
    posted_ = 0;
  }
  bool exchange_device(const DeviceSpan& left, const DeviceSpan& right) override {
    node_.dev_left_[local_] = left;
    node_.dev_right_[local_] = right;
    node_.wait();
    if (leader()) node_.exchange_device_across_ranks(left_of(node_.first_slab()), right_of(node_.first_slab() + node_.local_ - 1));
    node_.wait();
    return true;
  }
  double min(double v) override {
    return reduce_double(v, MPI_MIN, [](double a, double b) { return std::min(a, b); });
  }
  double max(double v) override {
    return reduce_double(v, MPI_MAX, [](double a, double b) { return std::max(a, b); });
  }
  std::int64_t sum(std::int64_t v) override {
    node_.islot_[local_] = v;
    node_.wait();
    if (leader()) {
      std::int64_t s = 0;
      for (auto x : node_.islot_) s += x;
      MPI_Allreduce(MPI_IN_PLACE, &s, 1, MPI_INT64_T, MPI_SUM, node_.comm_);
      node_.iresult_ = s;
    }
    node_.wait();
    return node_.iresult_;
  }
  void sum(std::vector<std::int64_t>& v) override {
    node_.vslot_[local_] = v;
    node_.wait();
    if (leader()) {
      std::vector<std::int64_t> s(v.size(), 0);
      for (auto& other : node_.vslot_)
        for (std::size_t k = 0; k < s.size(); ++k) s[k] += other[k];
      MPI_Allreduce(MPI_IN_PLACE, s.data(), static_cast<int>(s.size()), MPI_INT64_T, MPI_SUM, node_.comm_);
      node_.vresult_ = std::move(s);
    }
    node_.wait();
    v = node_.vresult_;
  }
  std::vector<Bytes> allgather(const Bytes& mine) override {
    node_.gslot_[local_] = mine;
    node_.wait();
    if (leader()) node_.allgather_across_ranks();
    node_.wait();
    return node_.gathered_;
  }
  std::vector<Bytes> gather(Bytes mine) override {
    node_.gslot_[local_] = std::move(mine);
    node_.wait();
    std::vector<Bytes> all;
    // Global slab 0 is rank 0's leader: it gathers and keeps the result.
    if (leader()) {
      node_.gather_to_rank0();
      if (slab_ == 0) all = std::move(node_.gathered_);
    }
    node_.wait();
    return all;
  }
  void barrier() override {
    node_.wait();
    if (leader()) MPI_Barrier(node_.comm_);
    node_.wait();
  }
  bool any(bool flag) override { return max(flag ? 1.0 : 0.0) > 0.0; }

 private:
  bool leader() const { return local_ == 0; }

  template <class Op>
  double reduce_double(double v, MPI_Op mpi_op, Op op) {
    node_.dslot_[local_] = v;
    node_.wait();
    if (leader()) {
      double r = node_.dslot_[0];
      for (int s = 1; s < node_.local_; ++s) r = op(r, node_.dslot_[s]);
      MPI_Allreduce(MPI_IN_PLACE, &r, 1, MPI_DOUBLE, mpi_op, node_.comm_);
      node_.dresult_ = r;
    }
    node_.wait();
    return node_.dresult_;
  }

  MpiNode& node_;
  int local_;
  int slab_;
  Bytes post_left_, post_right_;  // kept alive until collect() completes their sends
  MPI_Request sends_[2] = {MPI_REQUEST_NULL, MPI_REQUEST_NULL};
  int posted_ = 0;
};

std::unique_ptr<SlabTransport> MpiNode::endpoint(int local, bool periodic_x) {
  auto t = std::make_unique<MpiTransport>(*this, local);
  t->periodic_x = periodic_x;
  return t;
}

}  // namespace

std::unique_ptr<LocalSlabs> make_mpi_slabs(int local_slabs) { return std::make_unique<MpiNode>(local_slabs); }

}  // namespace spate
