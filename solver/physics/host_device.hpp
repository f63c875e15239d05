#pragma once
// One physics source for both backends: every function in solver/physics is marked SPATE_HD so
// that the OpenMP driver and the CUDA driver compile the same body.
#if defined(__CUDACC__)
#define SPATE_HD __host__ __device__ __forceinline__
#else
#define SPATE_HD inline
#endif
