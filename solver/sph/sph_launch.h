// The one place SPH's loops are launched: OpenMP loops over particles (and over slabs of cells for the
// pair-once scatter) today; a CUDA kernel launch can take their place later without touching the physics
// (sph_kernels.h) or the loop bodies.
#pragma once
#include <cstddef>

namespace flume::sph {

template <class Body>
void parallel_for(std::size_t n, const Body& body) {
#pragma omp parallel for schedule(static)
  for (long i = 0; i < static_cast<long>(n); ++i) body(static_cast<std::size_t>(i));
}

// body(s) for s < n in `colours` rounds, s = c, c + colours, ... in round c: the calls of one round run at
// once, the rounds one after the other. For a scatter whose writes from item s reach only items s - 1 .. s +
// 1 (slabs of cells, each wider than the kernel's reach): items three apart never write the same place, and
// each item's sums arrive in one order whatever the number of threads.
template <class Body>
void coloured_for(int n, int colours, const Body& body) {
  for (int c = 0; c < colours; ++c) {
#pragma omp parallel for schedule(dynamic, 1)
    for (int s = c; s < n; s += colours) body(s);
  }
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
