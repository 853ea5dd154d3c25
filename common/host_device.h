// FLUME_HD marks a function that both backends call: a host/device function when nvcc compiles it, an
// always-inlined host function otherwise. Every physics header (MPM and SPH) takes it from here.
#pragma once

#if defined(__CUDACC__)
#define FLUME_HD __host__ __device__ __forceinline__
#else
#define FLUME_HD inline __attribute__((always_inline))
#endif
