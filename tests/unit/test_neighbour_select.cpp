// The support selection of the CPU pair loops: the SIMD versions (AVX-512 where the build targets
// it, AVX2's permutation on any CPU with AVX2) must give exactly the list of the portable one, in
// the same order, for any candidate count (full 16- and 8-wide groups and a remainder) and for
// values on, just inside and just outside the bound.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "backend/cpu/neighbour_select.hpp"

namespace spate {

TEST(NeighbourSelect, SimdAndPortableSelectTheSameCandidatesInOrder) {
  const float limit = 0.25f;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> r2(0.0f, 2.0f * limit);
  for (int n : {0, 1, 15, 16, 17, 31, 32, 100, 1117}) {
    std::vector<float> d(n);
    for (int q = 0; q < n; ++q) {
      d[q] = r2(rng);
      if (q % 11 == 0) d[q] = limit;                                      // on the bound: outside
      if (q % 13 == 0) d[q] = std::nextafter(limit, 0.0f);                // just inside
      if (q % 17 == 0) d[q] = std::numeric_limits<float>::quiet_NaN();    // never inside
    }
    std::vector<std::uint32_t> a(n + cpu::kSelectSlack), b(n + cpu::kSelectSlack);
    const int na = cpu::select_inside(d.data(), n, limit, a.data());
    const int nb = cpu::select_inside_portable(d.data(), n, limit, b.data());
#if defined(__x86_64__)
    // The AVX2 permutation, whatever the build targets, where this CPU has AVX2.
    if (__builtin_cpu_supports("avx2")) {
      std::vector<std::uint32_t> c(n + cpu::kSelectSlack);
      ASSERT_EQ(cpu::select_inside_avx2(d.data(), n, limit, c.data()), nb) << "n = " << n;
      for (int k = 0; k < nb; ++k) EXPECT_EQ(c[k], b[k]) << "AVX2, n = " << n << ", entry " << k;
    }
#endif
    int expected = 0;
    for (int q = 0; q < n; ++q) expected += d[q] < limit;
    ASSERT_EQ(na, expected) << "n = " << n;
    ASSERT_EQ(nb, expected) << "n = " << n;
    for (int k = 0; k < na; ++k) {
      EXPECT_EQ(a[k], b[k]) << "n = " << n << ", entry " << k;
      EXPECT_LT(d[a[k]], limit);
    }
  }
}

// The transposing gather (8 records at a time with AVX2, then one by one) must hand the pair terms
// exactly the fields of the selected candidates, in the selection order.
TEST(NeighbourSelect, RecordGatherDeliversTheSelectedFieldsInOrder) {
  std::mt19937 rng(11);
  std::vector<cpu::NeighbourRecord> records(100);
  for (std::size_t q = 0; q < records.size(); ++q)
    for (int f = 0; f < 8; ++f) records[q].f[f] = static_cast<float>(q) + 0.125f * static_cast<float>(f);
  std::uniform_int_distribution<std::uint32_t> pick(0, 99);
  for (int count : {0, 1, 7, 8, 9, 16, 37}) {
    std::vector<std::uint32_t> index(count);
    for (auto& q : index) q = pick(rng);
    std::vector<float> out[8];
    float* fields[8];
    for (int f = 0; f < 8; ++f) out[f].assign(count + 1, -1.0f), fields[f] = out[f].data();
    cpu::gather_records(records.data(), index.data(), count, fields);
    for (int n = 0; n < count; ++n)
      for (int f = 0; f < 8; ++f) ASSERT_EQ(out[f][n], records[index[n]].f[f]) << "count " << count << ", n " << n << ", field " << f;
    for (int f = 0; f < 8; ++f) EXPECT_EQ(out[f][count], -1.0f) << "wrote past the end";
  }
}

// The pair gather (heat transfer's temperature and conductivity: eight pairs at a time with AVX2,
// then one by one) hands each field of the selected pairs in the selection order.
TEST(NeighbourSelect, PairGatherSplitsTheSelectedPairsInOrder) {
  std::mt19937 rng(12);
  std::vector<cpu::FieldPair> pairs(100);
  for (std::size_t q = 0; q < pairs.size(); ++q) pairs[q] = {300.0f + static_cast<float>(q), 0.5f + 0.25f * static_cast<float>(q)};
  std::uniform_int_distribution<std::uint32_t> pick(0, 99);
  for (int count : {0, 1, 7, 8, 9, 16, 23, 64}) {
    std::vector<std::uint32_t> index(count);
    for (auto& q : index) q = pick(rng);
    std::vector<float> a(count + 1, -1.0f), b(count + 1, -1.0f);
    cpu::gather_pairs(pairs.data(), index.data(), count, a.data(), b.data());
    for (int n = 0; n < count; ++n) {
      ASSERT_EQ(a[n], pairs[index[n]].a) << "count " << count << ", n " << n;
      ASSERT_EQ(b[n], pairs[index[n]].b) << "count " << count << ", n " << n;
    }
    EXPECT_EQ(a[count], -1.0f) << "wrote past the end";
    EXPECT_EQ(b[count], -1.0f) << "wrote past the end";
  }
}

}  // namespace spate
