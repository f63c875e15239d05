// The MPI transport against the definition of SlabTransport: on R ranks x D devices every slab must
// receive exactly its neighbours' messages (periodic x included, which no shipped case exercises)
// and every collective must give the exact all-slab result in slab order. Run under mpiexec with
// 2 or 3 ranks (ctest label mpi); without several ranks the tests skip.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

#include "../unit/host_copies.hpp"
#include "backend/cuda/halo_exchange.hpp"
#include "comm/mpi_transport.hpp"
#include "comm/process_group.hpp"

namespace spate {
namespace {

Bytes bytes(const std::string& s) { return Bytes(s.begin(), s.end()); }
std::string text(const Bytes& b) { return std::string(b.begin(), b.end()); }

// A message whose length depends on the sender, so that sizes are checked too (slab 3 sends nothing).
std::string message(char kind, int slab, int round) {
  if (slab == 3) return {};
  return std::string(1, kind) + std::to_string(slab) + "/" + std::to_string(round) + std::string(static_cast<std::size_t>(slab) * 7, '.');
}

// Runs body on every local slab, one thread each with local slab 0 on this thread, as Simulation::run does.
template <class Body>
void on_every_slab(LocalSlabs& local, bool periodic_x, Body body) {
  std::vector<std::string> errors(local.local_slabs());
  auto run = [&](int d) {
    try {
      auto t = local.endpoint(d, periodic_x);
      body(*t);
    } catch (const std::exception& e) {
      errors[d] = e.what();
      local.abandon();
    }
  };
  std::vector<std::thread> pool;
  for (int d = 1; d < local.local_slabs(); ++d) pool.emplace_back(run, d);
  run(0);
  for (auto& th : pool) th.join();
  for (auto& e : errors) EXPECT_EQ(e, "");
}

class MpiTransportTest : public ::testing::TestWithParam<std::tuple<int, bool>> {
 protected:
  void SetUp() override {
    if (process_group().ranks < 2) GTEST_SKIP() << "needs mpiexec with at least 2 ranks";
  }
};

TEST_P(MpiTransportTest, NeighbourMessagesArriveFromTheRightSlab) {
  const auto [devices, periodic] = GetParam();
  auto local = make_mpi_slabs(devices);
  const int S = local->slab_count();
  ASSERT_EQ(S, process_group().ranks * devices);
  ASSERT_EQ(local->first_slab(), process_group().rank * devices);
  on_every_slab(*local, periodic, [&](SlabTransport& t) {
    const int s = t.slab();
    for (int round = 0; round < 3; ++round) {
      Bytes from_left, from_right;
      t.exchange(bytes(message('L', s, round)), bytes(message('R', s, round)), from_left, from_right);
      const int l = t.left_of(s), r = t.right_of(s);
      EXPECT_EQ(text(from_left), l >= 0 ? message('R', l, round) : "") << "slab " << s << " round " << round;
      EXPECT_EQ(text(from_right), r >= 0 ? message('L', r, round) : "") << "slab " << s << " round " << round;
    }
  });
}

// post()/collect() (the halo refresh): the same neighbour messages, with the ranks running apart
// (each slab sleeps a different time before posting) and an exchange() between a post and its
// collect in one round.
TEST_P(MpiTransportTest, PostedMessagesArriveFromTheRightSlab) {
  const auto [devices, periodic] = GetParam();
  auto local = make_mpi_slabs(devices);
  on_every_slab(*local, periodic, [&](SlabTransport& t) {
    const int s = t.slab();
    const int l = t.left_of(s), r = t.right_of(s);
    for (int round = 0; round < 4; ++round) {
      std::this_thread::sleep_for(std::chrono::milliseconds((s * 3 + round) % 4));
      t.post(bytes(message('L', s, round)), bytes(message('R', s, round)));
      if (round == 2) {
        Bytes a, b;
        t.exchange(bytes("x"), bytes("y"), a, b);
        EXPECT_EQ(text(a), l >= 0 ? "y" : "");
        EXPECT_EQ(text(b), r >= 0 ? "x" : "");
      }
      Bytes from_left, from_right;
      t.collect(from_left, from_right);
      EXPECT_EQ(text(from_left), l >= 0 ? message('R', l, round) : "") << "slab " << s << " round " << round;
      EXPECT_EQ(text(from_right), r >= 0 ? message('L', r, round) : "") << "slab " << s << " round " << round;
    }
  });
}

TEST_P(MpiTransportTest, LargeMessagesCrossRanks) {
  const auto [devices, periodic] = GetParam();
  auto local = make_mpi_slabs(devices);
  on_every_slab(*local, periodic, [&](SlabTransport& t) {
    const int s = t.slab();
    Bytes big(3u << 20);  // past any eager limit
    std::iota(big.begin(), big.end(), static_cast<char>(s));
    Bytes from_left, from_right;
    t.exchange(big, big, from_left, from_right);
    const int l = t.left_of(s);
    if (l >= 0) {
      ASSERT_EQ(from_left.size(), big.size());
      EXPECT_EQ(from_left[0], static_cast<char>(l));
      EXPECT_EQ(from_left.back(), static_cast<char>(l + static_cast<int>(big.size()) - 1));
    }
  });
}

// The CUDA backend's halo protocol (backend/cuda/halo_exchange.hpp), staged through host memory
// (the default) and as built with SPATE_CUDA_AWARE_MPI, with host memory standing in for every GPU
// (MPI takes host and device pointers alike): neighbours on other ranks go through the transport's
// messages or buffer to buffer through exchange_device, those on this rank by "peer" copies.
// Every payload must arrive, three rounds running.
TEST_P(MpiTransportTest, GpuHaloProtocolDeliversEveryPayload) {
  const auto [devices, periodic] = GetParam();
  auto local = make_mpi_slabs(devices);
  for (const bool cuda_aware : {false, true})
  on_every_slab(*local, periodic, [&](SlabTransport& t) {
    const int s = t.slab();
    gpu::HostCopies copies(s % devices);
    gpu::HaloExchange halo(cuda_aware);
    for (int round = 0; round < 3; ++round) {
      const std::string out[2] = {message('L', s, round), message('R', s, round)};
      const std::array<gpu::Outgoing, 2> o{gpu::Outgoing{out[0].data(), out[0].size(), out[0].size()},
                                           gpu::Outgoing{out[1].data(), out[1].size(), out[1].size()}};
      const auto counts = halo.exchange(t, copies, o);
      const int l = t.left_of(s), r = t.right_of(s);
      const std::string got_left(copies.in[kLeft].begin(), copies.in[kLeft].end());
      const std::string got_right(copies.in[kRight].begin(), copies.in[kRight].end());
      EXPECT_EQ(counts[kLeft], l >= 0 ? message('R', l, round).size() : 0u) << "slab " << s;
      if (l >= 0) {
        EXPECT_EQ(got_left, message('R', l, round)) << "slab " << s << " round " << round;
      }
      if (r >= 0) {
        EXPECT_EQ(got_right, message('L', r, round)) << "slab " << s << " round " << round;
      }
    }
    for (Side side : {kLeft, kRight}) {
      const int n = side == kLeft ? t.left_of(s) : t.right_of(s);
      const gpu::HaloLink remote = cuda_aware ? gpu::HaloLink::DeviceMpi : gpu::HaloLink::Staged;
      const gpu::HaloLink want = n < 0 ? gpu::HaloLink::None : t.shares_memory_with(n) ? gpu::HaloLink::Peer : remote;
      EXPECT_EQ(halo.links()[side], want) << "slab " << s << " side " << side;
    }
  });
}

TEST_P(MpiTransportTest, CollectivesAreExactOverAllSlabs) {
  const auto [devices, periodic] = GetParam();
  auto local = make_mpi_slabs(devices);
  const int S = local->slab_count();
  on_every_slab(*local, periodic, [&](SlabTransport& t) {
    const int s = t.slab();
    EXPECT_EQ(t.min(10.0 + s), 10.0);
    EXPECT_EQ(t.max(10.0 + s), 10.0 + S - 1);
    EXPECT_EQ(t.min(s == 1 ? -0.25 : 1e300), -0.25);
    EXPECT_EQ(t.sum(static_cast<std::int64_t>(s) + (std::int64_t{1} << 40)), S * (S - 1) / 2 + S * (std::int64_t{1} << 40));
    std::vector<std::int64_t> v(5, 0);
    v[s % 5] = s + 1;
    t.sum(v);
    std::vector<std::int64_t> expected(5, 0);
    for (int k = 0; k < S; ++k) expected[k % 5] += k + 1;
    EXPECT_EQ(v, expected);
    const auto all = t.allgather(bytes(message('G', s, 0)));
    ASSERT_EQ(static_cast<int>(all.size()), S);
    for (int k = 0; k < S; ++k) EXPECT_EQ(text(all[k]), message('G', k, 0));
    // gather: everything on slab 0 only, in slab order (the checkpoint writer's collective).
    const auto at_writer = t.gather(bytes(message('W', s, 0)));
    if (s == 0) {
      ASSERT_EQ(static_cast<int>(at_writer.size()), S);
      for (int k = 0; k < S; ++k) EXPECT_EQ(text(at_writer[k]), message('W', k, 0));
    } else {
      EXPECT_TRUE(at_writer.empty());
    }
    EXPECT_TRUE(t.any(s == S - 1));
    EXPECT_FALSE(t.any(false));
    t.barrier();
  });
}

INSTANTIATE_TEST_SUITE_P(RanksTimesDevices, MpiTransportTest,
                         ::testing::Combine(::testing::Values(1, 2, 3), ::testing::Bool()),
                         [](const auto& p) {
                           return "devices" + std::to_string(std::get<0>(p.param)) +
                                  (std::get<1>(p.param) ? "_periodic" : "_walled");
                         });

}  // namespace
}  // namespace spate

int main(int argc, char** argv) {
  spate::init_process_group(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int failed = RUN_ALL_TESTS();
  spate::finalize_process_group();
  return failed;
}
