// The Solver interface hands particle positions and velocities out as n x 3 doubles (the unused axes 0);
// every backend keeps them per axis. One copy for all of them.
#pragma once
#include <cstddef>
#include <vector>

namespace flume {

// axes[d][i]: component d of particle i, for d < D (any indexable array of any number type).
template <int D, typename Array>
void interleave_axes(const Array* axes, size_t n, std::vector<double>& out) {
  out.assign(3 * n, 0.0);
  for (size_t i = 0; i < n; ++i)
    for (int d = 0; d < D; ++d) out[3 * i + d] = double(axes[d][i]);
}

}  // namespace flume
