#pragma once
// Selecting the candidates inside the kernel support, for the OpenMP pair loops. Only about 1
// candidate in 7 of the 27 cells around a particle is inside the support (3D, h = 1.73 dp), so
// this selection, not the pair terms, is most of a neighbour pass once the pair terms are
// vectorised. Both versions write the same list in the same (increasing) order, so which one runs
// never changes a result.
#include <cstdint>

#include "../../particles/particle_store.hpp"
#include "../../physics/host_device.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include <array>

namespace spate::cpu {

// Room select_inside() may write beyond the last selected entry.
constexpr int kSelectSlack = 16;

// Writes the numbers q in [0, n) with r2[q] < limit to index, in increasing order, and returns how
// many there are. Branch-free (a branch on "inside" mispredicts about every seventh candidate).
// From candidate q on, with `count` already selected (also the SIMD versions' tails).
inline int select_inside_from(const float* r2, int q, int n, float limit, std::uint32_t* index, int count) {
  for (; q < n; ++q) {
    index[count] = static_cast<std::uint32_t>(q);
    count += r2[q] < limit;
  }
  return count;
}
inline int select_inside_portable(const float* r2, int n, float limit, std::uint32_t* index) {
  return select_inside_from(r2, 0, n, limit, index, 0);
}

// r2[q] = |x - (cx[0][q], cx[1][q], ...)|^2 for the n candidates of a cell, the components added in
// the order of distance_squared() (particles/particle_access.hpp), so a candidate passes the
// support test here exactly when the per-particle body would keep it. Vectorised over candidates.
template <int Dim, class Point>
inline void candidate_distances(const Point& x, float* const (&cx)[Dim], int n, float* __restrict r2) {
  for (int q = 0; q < n; ++q) {  // must vectorise: candidate-distances
    float d2 = 0.0f;
    SPATE_UNROLL for (int k = 0; k < Dim; ++k) {
      const float d = x[k] - cx[k][q];
      d2 += d * d;
    }
    r2[q] = d2;
  }
}

#if defined(__x86_64__)
// For each 8-bit mask of inside candidates, the positions of its set bits in increasing order,
// one per 4-bit nibble (the permutation that compresses 8 lanes: select_inside_avx2).
constexpr std::array<std::uint32_t, 256> kCompressNibbles = [] {
  std::array<std::uint32_t, 256> t{};
  for (int m = 0; m < 256; ++m) {
    std::uint32_t v = 0;
    int k = 0;
    for (int b = 0; b < 8; ++b)
      if ((m >> b) & 1) v |= static_cast<std::uint32_t>(b) << (4 * k++);
    t[m] = v;
  }
  return t;
}();

// select_inside for AVX2 (x86-64-v3), which has no compress instruction: 8 candidates at a time,
// their comparison mask picks the permutation that moves the inside ones to the front, in order;
// all 8 lanes are stored and the count advances by the inside ones (the rest is overwritten next).
// On the AVX2 build the scalar selection was a third of the fluid pass (issue 36). Compiled for
// AVX2 whatever the build targets, so that the unit test checks it on any machine that has AVX2.
[[gnu::target("avx2")]] inline int select_inside_avx2(const float* r2, int n, float limit, std::uint32_t* index) {
  const __m256 bound = _mm256_set1_ps(limit);
  const __m256i shifts = _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28);
  const __m256i nibble = _mm256_set1_epi32(15);
  int count = 0, q = 0;
  for (; q + 8 <= n; q += 8) {
    // Ordered, non-signalling "<": false for NaN, like the scalar comparison.
    const int inside = _mm256_movemask_ps(_mm256_cmp_ps(_mm256_loadu_ps(r2 + q), bound, _CMP_LT_OQ));
    const __m256i lanes = _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32(static_cast<int>(kCompressNibbles[inside])), shifts), nibble);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(index + count), _mm256_add_epi32(lanes, _mm256_set1_epi32(q)));
    count += __builtin_popcount(static_cast<unsigned>(inside));
  }
  return select_inside_from(r2, q, n, limit, index, count);
}
#endif

// The same with AVX-512 compress where the build targets it (16 candidates per instruction
// group), with AVX2's permutation otherwise. index needs room for n + kSelectSlack entries.
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
  return select_inside_from(r2, q, n, limit, index, count);
#elif defined(__AVX2__)
  return select_inside_avx2(r2, n, limit, index);
#else
  return select_inside_portable(r2, n, limit, index);
#endif
}

// to[n] = from[index[n]] for n in [0, count): the selected neighbours' fields, contiguous for the
// vectorised pair terms. This is about a third of the fluid pass; neither the AVX-512 hardware
// gather nor a scalar (non-vectorised) loop was faster on the development machine than what GCC
// makes of this loop.
template <class T>
void gather(const T* __restrict from, const std::uint32_t* __restrict index, int count, T* __restrict to) {
  for (int n = 0; n < count; ++n) to[n] = from[index[n]];  // must vectorise: neighbour-gather
}

// Two fields of a candidate side by side (heat transfer's temperature and conductivity in the
// fluid pass), so that a selected neighbour's pair is one 8-byte load.
struct alignas(8) FieldPair {
  float a, b;
};

// a[n] = pairs[index[n]].a, b[n] = pairs[index[n]].b for n in [0, count). On AVX2 eight pairs are
// loaded as four 16-byte halves and split by two shuffles and two permutes: half the loads and
// about half the instructions of gathering the two fields separately (GCC's gather loop above
// takes three instructions per element and field on x86-64-v3).
[[gnu::always_inline]] inline void gather_pairs(const FieldPair* __restrict pairs, const std::uint32_t* __restrict index, int count,
                                                float* __restrict a, float* __restrict b) {
  int n = 0;
#if defined(__AVX2__)
  const auto half = [&](int q) {  // pairs index[q], index[q + 1] as (a, b, a, b)
    const __m128 lo = _mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(pairs + index[q])));
    return _mm_loadh_pi(lo, reinterpret_cast<const __m64*>(pairs + index[q + 1]));
  };
  for (; n + 8 <= count; n += 8) {
    // (a0 b0 a1 b1 | a2 b2 a3 b3) and (a4 b4 a5 b5 | a6 b6 a7 b7)
    const __m256 p0 = _mm256_insertf128_ps(_mm256_castps128_ps256(half(n)), half(n + 2), 1);
    const __m256 p1 = _mm256_insertf128_ps(_mm256_castps128_ps256(half(n + 4)), half(n + 6), 1);
    // (a0 a1 a4 a5 | a2 a3 a6 a7), then the 64-bit quarters in the order 0 2 1 3
    const __m256 ea = _mm256_shuffle_ps(p0, p1, _MM_SHUFFLE(2, 0, 2, 0));
    const __m256 eb = _mm256_shuffle_ps(p0, p1, _MM_SHUFFLE(3, 1, 3, 1));
    _mm256_storeu_ps(a + n, _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(ea), _MM_SHUFFLE(3, 1, 2, 0))));
    _mm256_storeu_ps(b + n, _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(eb), _MM_SHUFFLE(3, 1, 2, 0))));
  }
#endif
  for (; n < count; ++n) a[n] = pairs[index[n]].a, b[n] = pairs[index[n]].b;
}

// A candidate's fields for the fluid pair terms as one 32-byte record: the registry's kNeighbour
// fields (field_registry.hpp: position, velocity, density, pressure), vectors with 3 components
// (the unused third 0 in 2D). Copying one record per selected neighbour (then transposing to the
// arrays the vectorised pair terms read) costs a fraction of gathering eight separate arrays
// element by element.
struct alignas(32) NeighbourRecord {
  float f[8];
};
constexpr int kRecX = neighbour_record_offset(kField_pos);
constexpr int kRecV = neighbour_record_offset(kField_vel);
constexpr int kRecRho = neighbour_record_offset(kField_density);
constexpr int kRecP = neighbour_record_offset(kField_pressure);

namespace detail {
template <int Dim>
inline void to_record(const FieldVector<float>& v, std::size_t j, float* out) {
  out[0] = v[j];
}
template <int Dim>
inline void to_record(const FieldVector<float> (&v)[3], std::size_t j, float* out) {
  SPATE_UNROLL for (int k = 0; k < 3; ++k) out[k] = k < Dim ? v[k][j] : 0.0f;
}
template <int Dim, class T>
inline void to_record(const T&, std::size_t, float*) {}  // never called: only float fields are packed
}  // namespace detail

// The record of particle j: every kNeighbour field at its registry offset. Always inlined: GCC's
// heuristics keep it out of line in some instantiations of the fluid loop, a call per candidate
// (about 1% of the step's instructions).
template <int Dim>
[[gnu::always_inline]] inline void fill_record(const ParticleStore& ps, std::size_t j, NeighbourRecord& r) {
#define SPATE_RECORD_FIELD(member, ...) \
  if constexpr (kParticleFields[kField_##member].has(kNeighbour)) detail::to_record<Dim>(ps.member, j, r.f + neighbour_record_offset(kField_##member));
  SPATE_PARTICLE_FIELDS(SPATE_RECORD_FIELD)
#undef SPATE_RECORD_FIELD
}

// out[f][n] = records[index[n]].f[f] for n in [0, count), f in [0, 8).
[[gnu::always_inline]] inline void gather_records(const NeighbourRecord* __restrict records, const std::uint32_t* __restrict index, int count,
                           float* const out[8]) {
  int n = 0;
#if defined(__AVX2__)
  for (; n + 8 <= count; n += 8) {
    // Eight records as rows of an 8 x 8 matrix, transposed so that row f holds field f.
    const __m256 r0 = _mm256_load_ps(records[index[n + 0]].f), r1 = _mm256_load_ps(records[index[n + 1]].f);
    const __m256 r2 = _mm256_load_ps(records[index[n + 2]].f), r3 = _mm256_load_ps(records[index[n + 3]].f);
    const __m256 r4 = _mm256_load_ps(records[index[n + 4]].f), r5 = _mm256_load_ps(records[index[n + 5]].f);
    const __m256 r6 = _mm256_load_ps(records[index[n + 6]].f), r7 = _mm256_load_ps(records[index[n + 7]].f);
    const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
    const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
    const __m256 t4 = _mm256_unpacklo_ps(r4, r5), t5 = _mm256_unpackhi_ps(r4, r5);
    const __m256 t6 = _mm256_unpacklo_ps(r6, r7), t7 = _mm256_unpackhi_ps(r6, r7);
    const __m256 u0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)), u1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 u2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)), u3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 u4 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0)), u5 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 u6 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0)), u7 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2));
    _mm256_storeu_ps(out[0] + n, _mm256_permute2f128_ps(u0, u4, 0x20));
    _mm256_storeu_ps(out[1] + n, _mm256_permute2f128_ps(u1, u5, 0x20));
    _mm256_storeu_ps(out[2] + n, _mm256_permute2f128_ps(u2, u6, 0x20));
    _mm256_storeu_ps(out[3] + n, _mm256_permute2f128_ps(u3, u7, 0x20));
    _mm256_storeu_ps(out[4] + n, _mm256_permute2f128_ps(u0, u4, 0x31));
    _mm256_storeu_ps(out[5] + n, _mm256_permute2f128_ps(u1, u5, 0x31));
    _mm256_storeu_ps(out[6] + n, _mm256_permute2f128_ps(u2, u6, 0x31));
    _mm256_storeu_ps(out[7] + n, _mm256_permute2f128_ps(u3, u7, 0x31));
  }
#endif
  for (; n < count; ++n)
    for (int f = 0; f < 8; ++f) out[f][n] = records[index[n]].f[f];
}

}  // namespace spate::cpu
