// The host-side arithmetic of the CUDA backend (backend/cuda/device_plan.hpp), on the CPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "backend/cuda/device_plan.hpp"
#include "particles/particle_store.hpp"

namespace spate::gpu {

TEST(CudaLaunchShape, CoversEveryItemWithTheFewestBlocks) {
  EXPECT_EQ(launch_shape(0).blocks, 0u);
  EXPECT_EQ(launch_shape(1).blocks, 1u);
  EXPECT_EQ(launch_shape(128).blocks, 1u);
  EXPECT_EQ(launch_shape(129).blocks, 2u);
  EXPECT_EQ(launch_shape(1000, 256).blocks, 4u);
  EXPECT_EQ(launch_shape(1000, 256).threads, 256u);
  for (std::size_t n : {1u, 127u, 128u, 129u, 100000u}) {
    const LaunchShape s = launch_shape(n);
    EXPECT_GE(static_cast<std::size_t>(s.blocks) * s.threads, n);
    EXPECT_LT(static_cast<std::size_t>(s.blocks - 1) * s.threads, n);
  }
  EXPECT_THROW(launch_shape(std::size_t{1} << 40, 128), std::length_error);  // 2^33 blocks
  EXPECT_THROW(launch_shape(10, 0), std::invalid_argument);
}

TEST(CudaCapacity, GrowsWithHeadroomInQuantaAndNeverShrinks) {
  EXPECT_EQ(grown_capacity(0, 0), 0u);
  EXPECT_EQ(grown_capacity(1, 0), kCapacityQuantum);
  const std::size_t c = grown_capacity(100000, 0);
  EXPECT_GE(c, 100000u + 100000u / 8);
  EXPECT_EQ(c % kCapacityQuantum, 0u);
  EXPECT_EQ(grown_capacity(100000, c), c);       // fits: no reallocation
  EXPECT_EQ(grown_capacity(10, c), c);           // never shrinks
  EXPECT_GT(grown_capacity(c + 1, c), c + 1);    // grows past the request
}

namespace {
// Host memory standing in for the device's in the growth tests: every block counted, and the
// n-th allocation fails (as cudaMalloc does when the GPU is full).
struct Ledger {
  int live = 0, allocations = 0, fail_at = -1;
};
Ledger* ledger = nullptr;
struct LedgerFree {
  void operator()(char* p) const noexcept {
    delete[] p;
    --ledger->live;
  }
};
using Block = std::unique_ptr<char, LedgerFree>;
Block allocate(std::size_t bytes) {
  if (ledger->allocations++ == ledger->fail_at) throw std::runtime_error("out of memory");
  ++ledger->live;
  return Block(new char[bytes]);
}
}  // namespace

TEST(CudaGrowth, AFailedGrowthLeavesEveryArrayAsItWasAndLeaksNothing) {
  // DeviceSlabArrays::reserve: the fields and keys grow together, keeping their particles.
  Ledger l;
  ledger = &l;
  {
    std::vector<Block> arrays;
    for (int k = 0; k < 3; ++k) {
      arrays.push_back(allocate(8));
      std::memset(arrays.back().get(), 'a' + k, 8);
    }
    std::vector<Block*> blocks{&arrays[0], &arrays[1], &arrays[2]};
    const std::vector<std::size_t> bytes{16, 16, 16}, keep{8, 8, 8};
    auto copy = [](char* to, const char* from, std::size_t n) { std::memcpy(to, from, n); };
    int waits = 0;
    for (int fail : {0, 1, 2}) {  // the first, second or third new block cannot be had
      l.allocations = 0;
      l.fail_at = fail;
      const std::vector<char*> old{arrays[0].get(), arrays[1].get(), arrays[2].get()};
      EXPECT_THROW(grow_all_or_nothing<Block>(blocks, bytes, keep, allocate, copy, [&] { ++waits; }), std::runtime_error);
      EXPECT_EQ(l.live, 3) << "the new blocks allocated before the failure are freed";
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(arrays[k].get(), old[k]) << "untouched";
        EXPECT_EQ(arrays[k].get()[7], 'a' + k);
      }
    }
    EXPECT_EQ(waits, 0);
    l.fail_at = -1;
    grow_all_or_nothing<Block>(blocks, bytes, keep, allocate, copy, [&] { ++waits; });
    EXPECT_EQ(waits, 1);
    EXPECT_EQ(l.live, 3) << "the old blocks are freed once replaced";
    for (int k = 0; k < 3; ++k) EXPECT_EQ(std::string(arrays[k].get(), 8), std::string(8, static_cast<char>('a' + k))) << "kept";
  }
  EXPECT_EQ(l.live, 0);
}

TEST(CudaGrowth, ABufferWhoseGrowthFailedIsEmptyNotASizeWithoutMemory) {
  // DeviceBuffer, StreamOrderedBuffer, PinnedBuffer: the old block goes first; if the new one
  // cannot be had, `bytes` must not promise the old size (a later reserve would return early and
  // hand out a null pointer).
  Ledger l;
  ledger = &l;
  {
    Growable<Block> b;
    b.reserve_discarding(100, allocate);
    EXPECT_GE(b.bytes, 100u);
    EXPECT_NE(b.data(), nullptr);
    b.reserve_discarding(50, allocate);  // fits: nothing happens
    EXPECT_EQ(l.allocations, 1);
    l.fail_at = l.allocations;
    EXPECT_THROW(b.reserve_discarding(1 << 20, allocate), std::runtime_error);
    EXPECT_EQ(b.bytes, 0u);
    EXPECT_EQ(b.data(), nullptr);
    EXPECT_EQ(l.live, 0);
    l.fail_at = -1;
    b.reserve_discarding(10, allocate);  // and it recovers
    EXPECT_GE(b.bytes, 10u);
    EXPECT_EQ(l.live, 1);
  }
  EXPECT_EQ(l.live, 0);
}

TEST(CudaFootprint, DeviceFieldsMatchTheHostStoreAndStayUnderBudget) {
  for (int dim : {2, 3}) {
    const DeviceFootprint f = device_footprint(dim);
    // The device holds exactly the host store's per-particle fields, the sort's words and one
    // scratch word.
    ParticleStore host(dim);
    std::size_t host_fields = 0;
    for (auto& field : host.fields()) host_fields += field.elem_size;
    EXPECT_EQ(f.field_bytes, host_fields) << dim << "D";
    EXPECT_EQ(f.field_bytes, staged_bytes(dim, FieldSet::All));
    EXPECT_EQ(f.sort_bytes, 4u + 16u + 8u);
    EXPECT_EQ(f.scratch_bytes, sizeof(float));
  }
  EXPECT_EQ(device_footprint(3).per_particle(), 101u);  // 69 bytes of fields + 28 of sort + 4 of scratch
  EXPECT_EQ(device_footprint(2).per_particle(), 85u);
  // Ghost payload in 3D: position, velocity (24), density, pressure, id (12), kind (1).
  EXPECT_EQ(staged_bytes(3, FieldSet::Ghost), 37u);
  EXPECT_EQ(staged_bytes(3, FieldSet::Refresh), 20u);  // velocity, density, pressure
  EXPECT_EQ(halo_bytes_per_ghost(3), 78u);
  // The budget: <= 150 bytes per particle on the device, headroom and ghosts included.
  Lattice L;
  L.dim = 3;
  L.cells[0] = 120;
  L.cells[1] = 40;
  L.cells[2] = 40;
  const std::int64_t n = 4'000'000;
  for (int devices : {1, 2, 4}) {
    std::int64_t owned = 0;
    std::size_t bytes = 0;
    for (auto& m : device_memory_per_slab(L, n, devices)) {
      owned += m.owned;
      bytes = std::max(bytes, m.bytes);
      EXPECT_GE(m.capacity, static_cast<std::size_t>(m.owned + m.ghosts));
      EXPECT_LE(static_cast<double>(m.bytes) / static_cast<double>(m.owned), 150.0) << devices << " GPUs";
    }
    EXPECT_GE(owned, n);
    EXPECT_LT(owned, n + devices);
    EXPECT_GT(bytes, static_cast<std::size_t>(n / devices) * 101);
  }
}

TEST(CudaSort, TheSortWordHoldsEveryKeyAboveEveryIdAndNoMore) {
  EXPECT_EQ(bits_for(0), 0);
  EXPECT_EQ(bits_for(1), 0);
  EXPECT_EQ(bits_for(2), 1);
  EXPECT_EQ(bits_for(3), 2);
  EXPECT_EQ(bits_for(4), 2);
  EXPECT_EQ(bits_for(5), 3);
  EXPECT_EQ(bits_for(std::uint64_t{1} << 32), 32);
  // The paper's case (dp = 0.002, 312 x 122 x 148 cells) on 4 GPUs: 12.8 million ids (24 bits),
  // 78 owned columns and an 80-column ghost box per GPU, 2.85 million keys (22 bits).
  const std::uint32_t paper_keys = 78 * 122 * 148 + 80 * 122 * 148 + 3;
  EXPECT_EQ(sort_word(paper_keys, 12'763'776).id_bits, 24);
  EXPECT_EQ(sort_word(paper_keys, 12'763'776).end_bit, 46);
  EXPECT_EQ(sort_word(0xffffffffu, 0xffffffffu).end_bit, 64);
  for (std::uint32_t keys : {1u, 2u, 3u, 1000u, 65537u, 4000000u})
    for (std::uint32_t ids : {1u, 2u, 1000u, 1u << 20, 12'763'776u}) {
      const SortWord w = sort_word(keys, ids);
      const std::uint64_t largest = static_cast<std::uint64_t>(keys - 1) << w.id_bits | (ids - 1);
      EXPECT_EQ(largest >> w.end_bit, 0u) << keys << " keys, " << ids << " ids";  // fits
      EXPECT_LT(static_cast<std::uint64_t>(ids - 1), std::uint64_t{1} << w.id_bits);  // ids never reach the key bits
      if (w.end_bit > 0) {
        EXPECT_NE(largest >> (w.end_bit - 1), 0u) << "a bit too many";
      }
    }
}

TEST(CudaFootprint, GhostColumnsOnlyWhereThereIsANeighbour) {
  Lattice L;
  L.dim = 2;
  L.cells[0] = 90;
  L.cells[1] = 30;
  const auto one = device_memory_per_slab(L, 9000, 1);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].ghosts, 0);
  EXPECT_EQ(one[0].owned, 9000);
  const auto three = device_memory_per_slab(L, 9000, 3);
  EXPECT_EQ(three[0].ghosts, 100);  // one neighbour: one column of 100 particles
  EXPECT_EQ(three[1].ghosts, 200);
  EXPECT_EQ(three[2].ghosts, 100);
  L.periodic[0] = true;
  EXPECT_EQ(device_memory_per_slab(L, 9000, 3)[0].ghosts, 200);
  EXPECT_THROW(device_memory_per_slab(L, 9000, 0), std::invalid_argument);
}

TEST(CudaVisibleDevices, ParsedAsTheRuntimeDoes) {
  EXPECT_FALSE(visible_devices(nullptr).has_value());
  EXPECT_TRUE(visible_devices("")->empty());
  EXPECT_TRUE(visible_devices("-1")->empty());
  EXPECT_EQ(*visible_devices("0,1"), (std::vector<std::string>{"0", "1"}));
  EXPECT_EQ(*visible_devices(" 2 , 3"), (std::vector<std::string>{"2", "3"}));
  // Everything from the first invalid entry on is ignored.
  EXPECT_EQ(*visible_devices("0,-1,1"), (std::vector<std::string>{"0"}));
  EXPECT_EQ(*visible_devices("GPU-8932f937,MIG-abc"), (std::vector<std::string>{"GPU-8932f937", "MIG-abc"}));
  EXPECT_NE(no_device_reason("").find("hides every device"), std::string::npos);
  EXPECT_NE(no_device_reason("-1").find("hides every device"), std::string::npos);
  EXPECT_NE(no_device_reason("0").find("found none"), std::string::npos);
  EXPECT_NE(no_device_reason(nullptr).find("no GPU"), std::string::npos);
}

TEST(CudaPairLoop, TheHalfWarpLoopUnlessThePerThreadOneIsAskedFor) {
  EXPECT_FALSE(per_thread_pair_loop(nullptr));
  EXPECT_FALSE(per_thread_pair_loop(""));
  EXPECT_FALSE(per_thread_pair_loop("lanes"));
  EXPECT_TRUE(per_thread_pair_loop("thread"));
  EXPECT_THROW(per_thread_pair_loop("threads"), std::invalid_argument);
  // The half-warp pass launches 16 threads per particle in whole warps, so a half-warp never
  // straddles two blocks.
  EXPECT_EQ(kThreadsPerBlock % 32u, 0u);
}

TEST(CudaDeviceAssignment, WorkersTakeConsecutiveDevicesPerNodeRank) {
  EXPECT_EQ(device_for_worker(0, 1, 0, 4), 0);
  EXPECT_EQ(device_for_worker(3, 4, 0, 4), 3);
  EXPECT_EQ(device_for_worker(1, 2, 1, 4), 3);  // rank 1 of the node drives GPUs 2 and 3
  EXPECT_EQ(device_for_worker(2, 4, 0, 2), 0);  // more workers than GPUs: shared, wrapping
  EXPECT_THROW(device_for_worker(0, 1, 0, 0), std::invalid_argument);
  EXPECT_THROW(device_for_worker(2, 2, 0, 4), std::invalid_argument);
}

namespace {
std::map<std::string, std::string> fake_env;
const char* fake_getenv(const char* name) {
  auto it = fake_env.find(name);
  return it == fake_env.end() ? nullptr : it->second.c_str();
}
}  // namespace

TEST(CudaDeviceAssignment, NodeLocalRankFromTheLauncher) {
  fake_env.clear();
  EXPECT_EQ(node_local_rank(fake_getenv), 0);
  fake_env["SLURM_LOCALID"] = "3";
  EXPECT_EQ(node_local_rank(fake_getenv), 3);
  fake_env["OMPI_COMM_WORLD_LOCAL_RANK"] = "1";  // Open MPI's own variable wins
  EXPECT_EQ(node_local_rank(fake_getenv), 1);
  fake_env["OMPI_COMM_WORLD_LOCAL_RANK"] = "x";  // unparsable: the next launcher's
  EXPECT_EQ(node_local_rank(fake_getenv), 3);
}

}  // namespace spate::gpu
