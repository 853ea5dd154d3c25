// One launch for the step's per-particle and per-node bodies (the AMReX ParallelFor habit, STYLE.md):
// parallel_for(n, f) calls f(i) for i in [0, n). On a GPU it is a CUDA kernel (Thrust's for_each over a
// counting range launches one); the CUDA source compiled for the host (FLUME_CUDA_EMULATION) runs it through
// Thrust's sequential system; the CPU backend runs it as an OpenMP loop. The bodies are the same FLUME_HD
// functions.
//
// Each build of it lives in its own inline namespace, so that the CPU's and the emulated CUDA backend's,
// linked into one program, are different functions rather than one function defined twice.
#pragma once
#include <cstddef>

#if defined(__CUDACC__) || defined(FLUME_CUDA_EMULATION)
#include <thrust/execution_policy.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#endif

namespace flume::mpm {

#if defined(__CUDACC__) || defined(FLUME_CUDA_EMULATION)
inline namespace launch_thrust {
template <typename F>
void parallel_for(size_t n, const F& f) {
  THRUST_NS_QUALIFIER::counting_iterator<size_t> first(0);
  THRUST_NS_QUALIFIER::for_each(THRUST_NS_QUALIFIER::device, first, first + n, f);
}
}  // namespace launch_thrust
#else
inline namespace launch_openmp {
template <typename F>
void parallel_for(size_t n, const F& f) {
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; ++i) f(i);
}
}  // namespace launch_openmp
#endif

}  // namespace flume::mpm
