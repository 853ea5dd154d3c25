// A dam break in a 3D tank, y across, mirror-symmetric about y = 0.2 m: the water fills the tank's width, and a
// column stands across the centreline downstream, with a load cell on it. `half`: only y <= 0.2 m, closed by a
// boundary of condition `plane` (symmetry or slip). `y_lo`: the domain's lower y, which decides whether the plane
// lies on a grid line (-0.06: 13 cells) or midway between two (-0.05: 12.5 cells). dx 0.02 m, double.
// tests/solver/test_symmetry.cpp and test_cuda.cpp.
#pragma once
#include <cstdio>
#include <string>

namespace flume::test {

inline std::string symmetric_tank(bool half, const std::string& plane, double y_lo, double end_time,
                                  double column_x = 0.4) {
  const double y_hi = half ? 0.26 : 0.46, water_hi = half ? 0.2 : 0.4;
  char text[4096];
  std::snprintf(text, sizeof text, R"({
    "name": "tank", "dimension": 3,
    "domain": {"lo": [-0.06, %g, -0.06], "hi": [0.66, %g, 0.5], "walls": "slip"},
    "solver": {"dx": 0.02, "ppc": 8, "cfl": 0.4, "precision": "double", "end_time": %g},
    "fluid": {"bulk_modulus": 2e5, "jbar_psi": 0.9},
    "boundaries": [
      {"name": "floor", "type": "half_space", "point": [0, 0, 0], "normal": [0, 0, 1], "condition": "slip"},
      {"name": "back", "type": "half_space", "point": [0, 0, 0], "normal": [1, 0, 0], "condition": "slip"},
      {"name": "end", "type": "half_space", "point": [0.6, 0, 0], "normal": [-1, 0, 0], "condition": "slip"},
      {"name": "side", "type": "half_space", "point": [0, 0, 0], "normal": [0, 1, 0], "condition": "slip"},
      {"name": "%s", "type": "half_space", "point": [0, %g, 0], "normal": [0, -1, 0], "condition": "%s"},
      {"name": "column", "type": "box", "lo": [%g, 0.17, -0.1], "hi": [%g, 0.23, 0.6], "condition": "slip"}],
    "water": [{"lo": [0, 0, 0], "hi": [0.2, %g, 0.3]}],
    "instruments": {"loads": [{"name": "column", "boundary": "column", "rate_hz": 100}]}
  })",
                y_lo, y_hi, end_time, half ? "plane" : "far_side", half ? 0.2 : 0.4, half ? plane.c_str() : "slip",
                column_x, column_x + 0.05, water_hi);
  return text;
}

}  // namespace flume::test
