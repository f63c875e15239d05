// The halo protocol of the CUDA backend (backend/cuda/halo_exchange.hpp) on the CPU: worker threads
// over an InProcessHub, host memory standing in for each GPU's memory, memcpy for every copy. What
// runs on a GPU is the same code with cudaMemcpy*Async behind DeviceCopies.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include "backend/cuda/halo_exchange.hpp"
#include "host_copies.hpp"
#include "comm/in_process_transport.hpp"

namespace spate::gpu {
namespace {

// An endpoint whose neighbour `remote` counts as another process (as over MPI).
class RemoteNeighbour final : public SlabTransport {
 public:
  RemoteNeighbour(std::unique_ptr<SlabTransport> inner, int remote) : inner_(std::move(inner)), remote_(remote) {
    periodic_x = inner_->periodic_x;
  }
  int slab() const override { return inner_->slab(); }
  int slab_count() const override { return inner_->slab_count(); }
  void exchange(const Bytes& l, const Bytes& r, Bytes& fl, Bytes& fr) override { inner_->exchange(l, r, fl, fr); }
  double min(double v) override { return inner_->min(v); }
  double max(double v) override { return inner_->max(v); }
  std::int64_t sum(std::int64_t v) override { return inner_->sum(v); }
  void sum(std::vector<std::int64_t>& v) override { inner_->sum(v); }
  std::vector<Bytes> allgather(const Bytes& b) override { return inner_->allgather(b); }
  std::vector<Bytes> gather(Bytes b) override { return inner_->gather(std::move(b)); }
  void barrier() override { inner_->barrier(); }
  bool any(bool f) override { return inner_->any(f); }
  bool shares_memory_with(int s) const override { return s != remote_; }

 private:
  std::unique_ptr<SlabTransport> inner_;
  int remote_;
};

// What slab s sends to `side` in round k: a recognisable pattern of (s + 1) * 4 + side particles.
std::vector<char> payload(int s, int side, int k) {
  std::vector<char> b(static_cast<std::size_t>((s + 1) * 4 + side) * 8);
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<char>(s * 31 + side * 7 + k * 3 + static_cast<int>(i));
  return b;
}

struct SlabResult {
  std::array<HaloLink, 2> links;
  int to_host = 0, from_host = 0, peer = 0;
  std::vector<int> peer_from;
  std::size_t received_bytes = 0;
};

// `slabs` workers with devices[s], three rounds of exchanges; checks every delivery.
std::vector<SlabResult> run(int slabs, bool periodic, const std::vector<int>& devices, const std::function<bool(int, int)>& reach,
                            int remote_face = -1, bool force_staged = false) {
  InProcessHub hub(slabs);
  std::vector<SlabResult> results(slabs);
  auto body = [&](int s) {
    std::unique_ptr<SlabTransport> t = hub.endpoint(s, periodic);
    // Faces between slab f and f + 1 at remote_face count as crossing a process boundary.
    if (remote_face >= 0 && (s == remote_face || s == (remote_face + 1) % slabs))
      t = std::make_unique<RemoteNeighbour>(std::move(t), s == remote_face ? (s + 1) % slabs : remote_face);
    HostCopies copies(devices[s], reach);
    HaloExchange halo(false, force_staged);
    std::size_t received = 0;
    for (int k = 0; k < 3; ++k) {
      std::vector<char> out[2] = {payload(s, kLeft, k), payload(s, kRight, k)};
      const std::array<Outgoing, 2> o{Outgoing{out[0].data(), out[0].size() / 8, out[0].size()},
                                      Outgoing{out[1].data(), out[1].size() / 8, out[1].size()}};
      const auto counts = halo.exchange(*t, copies, o);
      // From the left neighbour: what it sent to its right, and vice versa.
      const int l = t->left_of(s), r = t->right_of(s);
      EXPECT_EQ(counts[kLeft], l < 0 ? 0u : payload(l, kRight, k).size() / 8) << "slab " << s;
      EXPECT_EQ(counts[kRight], r < 0 ? 0u : payload(r, kLeft, k).size() / 8) << "slab " << s;
      if (l >= 0) {
        received += payload(l, kRight, k).size();
        EXPECT_EQ(copies.in[kLeft], payload(l, kRight, k)) << "slab " << s << " round " << k;
      }
      if (r >= 0) {
        received += payload(r, kLeft, k).size();
        EXPECT_EQ(copies.in[kRight], payload(r, kLeft, k)) << "slab " << s << " round " << k;
      }
    }
    EXPECT_EQ(copies.unfenced_incoming, 0) << "slab " << s << ": an incoming buffer asked for before its readers were waited for";
    results[s] = {halo.links(), copies.to_host, copies.from_host, copies.peer, copies.peer_from, received};
  };
  std::vector<std::thread> pool;
  for (int s = 0; s < slabs; ++s) pool.emplace_back(body, s);
  for (auto& th : pool) th.join();
  return results;
}

}  // namespace

TEST(HaloExchange, LinkChoiceIsTheSameAtBothEnds) {
  EXPECT_EQ(choose_halo_link(false, true, 0, 1, true, false), HaloLink::None);
  EXPECT_EQ(choose_halo_link(true, true, 0, 1, true, false), HaloLink::Peer);
  EXPECT_EQ(choose_halo_link(true, true, 0, 1, false, false), HaloLink::Staged);
  EXPECT_EQ(choose_halo_link(true, true, 2, 2, false, false), HaloLink::Peer);  // one GPU shared by two workers
  EXPECT_EQ(choose_halo_link(true, false, 0, 0, true, false), HaloLink::Staged);  // another rank: never peer
  EXPECT_EQ(choose_halo_link(true, false, 0, 1, true, true), HaloLink::DeviceMpi);
}

TEST(HaloExchange, PeerWhereDevicesReachEachOtherStagedElsewhere) {
  // GPUs 0-1 and 2-3 reach each other (two NVLink pairs), nothing else; periodic x closes the ring.
  auto reach = [](int a, int b) { return a / 2 == b / 2; };
  const auto r = run(4, true, {0, 1, 2, 3}, reach);
  EXPECT_EQ(r[0].links[kRight], HaloLink::Peer);
  EXPECT_EQ(r[1].links[kLeft], HaloLink::Peer);
  EXPECT_EQ(r[1].links[kRight], HaloLink::Staged);
  EXPECT_EQ(r[2].links[kLeft], HaloLink::Staged);
  EXPECT_EQ(r[3].links[kRight], HaloLink::Staged);  // 3 -> 0 across the periodic boundary
  EXPECT_EQ(r[0].links[kLeft], HaloLink::Staged);
  // Three rounds: slab 1 pulls from GPU 0 by peer copy, stages to and from host on its right.
  EXPECT_EQ(r[1].peer, 3);
  EXPECT_EQ(r[1].peer_from, (std::vector<int>{0, 0, 0}));
  EXPECT_EQ(r[1].to_host, 3);
  EXPECT_EQ(r[1].from_host, 3);
}

TEST(HaloExchange, SharedGpuAndEdgesWithoutNeighbours) {
  // Three workers on one GPU (more workers than GPUs), non-periodic: device-local copies, and
  // nothing crosses the outer faces.
  const auto r = run(3, false, {0, 0, 0}, [](int, int) { return false; });
  EXPECT_EQ(r[0].links[kLeft], HaloLink::None);
  EXPECT_EQ(r[0].links[kRight], HaloLink::Peer);
  EXPECT_EQ(r[2].links[kRight], HaloLink::None);
  EXPECT_EQ(r[1].to_host + r[1].from_host, 0);
}

TEST(HaloExchange, StagedLinksCanBeForcedOnOneGpu) {
  // SPATE_CUDA_HALO_LINK=staged: three workers sharing GPU 0 in a periodic ring, every halo
  // through pinned host memory (the path of GPUs without peer access, and of other ranks), and the
  // process's traffic counters say so.
  EXPECT_FALSE(staged_links_forced(nullptr));
  EXPECT_FALSE(staged_links_forced(""));
  EXPECT_FALSE(staged_links_forced("auto"));
  EXPECT_TRUE(staged_links_forced("staged"));
  EXPECT_THROW(staged_links_forced("peer"), std::invalid_argument);
  EXPECT_EQ(choose_halo_link(true, true, 0, 0, true, false, true), HaloLink::Staged);
  EXPECT_EQ(choose_halo_link(true, false, 0, 1, true, true, true), HaloLink::DeviceMpi);  // other ranks keep theirs
  const HaloTraffic before = halo_traffic();
  const auto r = run(3, true, {0, 0, 0}, [](int, int) { return true; }, -1, true);
  const HaloTraffic after = halo_traffic();
  std::size_t received = 0;
  for (const auto& s : r) {
    EXPECT_EQ(s.links[kLeft], HaloLink::Staged);
    EXPECT_EQ(s.links[kRight], HaloLink::Staged);
    EXPECT_EQ(s.peer, 0);
    EXPECT_EQ(s.from_host, 6);  // both sides, three rounds
    received += s.received_bytes;
  }
  EXPECT_EQ(after.staged_bytes - before.staged_bytes, received);
  EXPECT_EQ(after.peer_bytes, before.peer_bytes);
  // Unforced, the same ring is all same-device copies.
  run(3, true, {0, 0, 0}, [](int, int) { return true; });
  const HaloTraffic unforced = halo_traffic();
  EXPECT_EQ(unforced.peer_bytes - after.peer_bytes, received);
  EXPECT_EQ(unforced.staged_bytes, after.staged_bytes);
}

TEST(HaloExchange, NeighboursInAnotherProcessGoThroughHostMemory) {
  // Every device reaches every other, but the face between slabs 1 and 2 crosses processes.
  const auto r = run(4, false, {0, 1, 0, 1}, [](int, int) { return true; }, 1);
  EXPECT_EQ(r[1].links[kRight], HaloLink::Staged);
  EXPECT_EQ(r[2].links[kLeft], HaloLink::Staged);
  EXPECT_EQ(r[1].links[kLeft], HaloLink::Peer);
  EXPECT_EQ(r[2].links[kRight], HaloLink::Peer);
}

}  // namespace spate::gpu
