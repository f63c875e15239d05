#pragma once
// One physics source for both backends: every function in solver/physics is marked SPATE_HD so
// that the OpenMP driver and the CUDA driver compile the same body.
#if defined(__CUDACC__)
#define SPATE_HD __host__ __device__ __forceinline__
#else
#define SPATE_HD inline
#endif

// Loops over vector components (2 or 3) must disappear before the vectoriser looks at a pair loop.
// nvcc compiles a .cu file twice: the device pass (__CUDA_ARCH__ defined) takes `#pragma unroll`;
// in the host pass neither spelling is accepted by both its front end and GCC (each warns about
// the other's), and no physics loop of a .cu file runs on the host, so the pragma is left out.
#if defined(__CUDA_ARCH__)
#define SPATE_UNROLL _Pragma("unroll")
#elif defined(__CUDACC__)
#define SPATE_UNROLL
#elif defined(__clang__)
#define SPATE_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define SPATE_UNROLL _Pragma("GCC unroll 4")
#else
#define SPATE_UNROLL
#endif

// A run option (the same for every pair of a loop) as a factor 1 or 0 of a branch-free pair term.
// Not `on ? 1.0f : 0.0f`: GCC 12 turns x * (on ? 1 : 0) into on ? x : x * 0, a select between
// per-pair values on a loop-invariant condition, which its vectoriser rejects ("relevant stmt not
// supported"), so the whole pair loop stayed scalar (scripts/check-vectorisation guards it).
SPATE_HD float option_factor(bool on) { return static_cast<float>(on); }
