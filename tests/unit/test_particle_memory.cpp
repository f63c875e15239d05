// Particle memory: on the heap until shared; then every particle array comes from one memfd arena
// that a second mapping (what the in-situ helper does) sees byte for byte, freed arrays give their
// space back and merge, and arrays allocated before sharing are still freed on the heap.
// Sharing is process-wide and one-way: CTest runs each test in its own process.
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>

#include "particles/particle_memory.hpp"
#include "particles/particle_store.hpp"

using namespace spate;

TEST(ParticleMemory, HeapUntilShared) {
  EXPECT_EQ(shared_particle_memory(), nullptr);
  FieldVector<float> a(1000, 1.5f);
  EXPECT_EQ(a[999], 1.5f);
  EXPECT_EQ(shared_particle_bytes_in_use(), 0u);
}

TEST(ParticleMemory, SharedArraysAreSeenByASecondMapping) {
  FieldVector<float> before(100, 2.0f);  // heap, freed on the heap after sharing
  const SharedParticleMemory& region = share_particle_memory();
  EXPECT_EQ(&region, shared_particle_memory());
  EXPECT_GE(region.size, std::size_t{1} << 30);
  EXPECT_FALSE(region.contains(before.data()));

  ParticleStore p(3);
  p.resize(5000);
  for (auto& f : p.fields()) EXPECT_TRUE(region.contains(f.bytes())) << f.name << " is not in the arena";
  for (std::size_t i = 0; i < p.size(); ++i) p.pos[0][i] = static_cast<float>(i) * 0.25f;

  // The helper's view: the same memfd mapped again (read-only) elsewhere in the address space.
  void* view = mmap(nullptr, region.size, PROT_READ, MAP_SHARED, region.fd, 0);
  ASSERT_NE(view, MAP_FAILED);
  const auto offset = reinterpret_cast<std::uintptr_t>(p.pos[0].data()) - region.base;
  const float* seen = reinterpret_cast<const float*>(static_cast<const char*>(view) + offset);
  EXPECT_EQ(std::memcmp(seen, p.pos[0].data(), p.size() * sizeof(float)), 0);
  p.pos[0][4321] = -7.0f;  // written after mapping: still the same pages
  EXPECT_EQ(seen[4321], -7.0f);
  munmap(view, region.size);

  before = FieldVector<float>(3, 1.0f);  // frees the heap block, allocates in the arena
  EXPECT_TRUE(region.contains(before.data()));
}

TEST(ParticleMemory, FreedBlocksMergeAndAreReused) {
  const SharedParticleMemory& region = share_particle_memory();
  const std::size_t base_use = shared_particle_bytes_in_use();
  const std::size_t n = 3 * 4096 / sizeof(float);  // three pages each
  auto* a = new FieldVector<float>(n);
  auto* b = new FieldVector<float>(n);
  auto* c = new FieldVector<float>(n);
  EXPECT_EQ(shared_particle_bytes_in_use(), base_use + 9 * 4096);
  const float* first = a->data();
  delete b;
  delete a;  // a and b merge into six free pages at a's place
  FieldVector<float> both(2 * n);
  EXPECT_EQ(both.data(), first);
  EXPECT_TRUE(region.contains(both.data()));
  for (float v : both) EXPECT_EQ(v, 0.0f);
  delete c;
  EXPECT_EQ(shared_particle_bytes_in_use(), base_use + 6 * 4096);
}
