// The quadratic B-spline weight the instruments read particles with: the grid's own stencil, so a gauge or a
// probe weighs water as a node would.
#pragma once
#include <cmath>

#include "common/host_device.h"

namespace flume {

// Weight of a distance q in cells (support 1.5 cells).
FLUME_HD double bspline_weight(double q) {
  q = std::fabs(q);
  return q < 0.5 ? 0.75 - q * q : (q < 1.5 ? 0.5 * (1.5 - q) * (1.5 - q) : 0.0);
}

}  // namespace flume
