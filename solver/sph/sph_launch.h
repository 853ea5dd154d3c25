// The one place SPH's loops are launched: an OpenMP loop over particles today; a CUDA kernel launch can take
// its place later without touching the physics (sph_kernels.h) or the loop bodies.
#pragma once
#include <cstddef>

namespace flume::sph {

template <class Body>
void parallel_for(std::size_t n, const Body& body) {
#pragma omp parallel for schedule(static)
  for (long i = 0; i < static_cast<long>(n); ++i) body(static_cast<std::size_t>(i));
}

// The largest of f(i) over i < n (0 when n = 0).
template <typename T, class F>
T parallel_max(std::size_t n, const F& f) {
  T m = T(0);
#pragma omp parallel for schedule(static) reduction(max : m)
  for (long i = 0; i < static_cast<long>(n); ++i) {
    const T v = f(static_cast<std::size_t>(i));
    m = v > m ? v : m;
  }
  return m;
}

}  // namespace flume::sph
