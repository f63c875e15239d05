#pragma once
// Selecting the candidates inside the kernel support, for the OpenMP pair loops. Only about 1
// candidate in 7 of the 27 cells around a particle is inside the support (3D, h = 1.73 dp), so
// this selection, not the pair terms, is most of a neighbour pass once the pair terms are
// vectorised. Both versions write the same list in the same (increasing) order, so which one runs
// never changes a result.
#include <cstdint>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace spate::cpu {

// Room select_inside() may write beyond the last selected entry.
constexpr int kSelectSlack = 16;

// Writes the numbers q in [0, n) with r2[q] < limit to index, in increasing order, and returns how
// many there are. Branch-free (a branch on "inside" mispredicts about every seventh candidate).
inline int select_inside_portable(const float* r2, int n, float limit, std::uint32_t* index) {
  int count = 0;
  for (int q = 0; q < n; ++q) {
    index[count] = static_cast<std::uint32_t>(q);
    count += r2[q] < limit;
  }
  return count;
}

// The same with AVX-512 compress where the build targets it (16 candidates per instruction
// group). index needs room for n + kSelectSlack entries.
inline int select_inside(const float* r2, int n, float limit, std::uint32_t* index) {
#if defined(__AVX512F__)
  const __m512 bound = _mm512_set1_ps(limit);
  const __m512i sixteen = _mm512_set1_epi32(16);
  __m512i q16 = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  int count = 0, q = 0;
  for (; q + 16 <= n; q += 16) {
    // Ordered, non-signalling "<": false for NaN, like the scalar comparison.
    const __mmask16 inside = _mm512_cmp_ps_mask(_mm512_loadu_ps(r2 + q), bound, _CMP_LT_OQ);
    _mm512_storeu_si512(index + count, _mm512_maskz_compress_epi32(inside, q16));
    count += __builtin_popcount(inside);
    q16 = _mm512_add_epi32(q16, sixteen);
  }
  for (; q < n; ++q) {
    index[count] = static_cast<std::uint32_t>(q);
    count += r2[q] < limit;
  }
  return count;
#else
  return select_inside_portable(r2, n, limit, index);
#endif
}

}  // namespace spate::cpu
