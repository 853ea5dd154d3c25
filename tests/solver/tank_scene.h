// A tank scene with one debris cube, shared by the debris and checkpoint tests.
#pragma once
#include <algorithm>
#include <cstdio>
#include <string>

namespace flume::test {

// A square tank (slip walls at 0 and L, floor at z_floor) filled to `depth` above its floor, with one box of
// edges `size` and density rho_b, its centre at height z_centre above the floor. The grid's lines lie at whole
// multiples of dx from 0 whatever z_floor, so a z_floor that is not one puts the floor between two lines (the
// Waseda apron at 0.255 m lies 0.75 of a cell above one at dx = 0.02 m).
inline std::string tank_scene(double L, double depth, const double size[3], double rho_b, double z_centre, double dx,
                              double end_time, double psi, double bulk_modulus, double z_floor = 0.0) {
  const double pad = 3 * dx;
  char buf[4096];
  std::snprintf(buf, sizeof buf, R"({
    "name": "tank", "dimension": 3,
    "domain": {"lo": [%g, %g, %g], "hi": [%g, %g, %g], "walls": "slip"},
    "solver": {"dx": %g, "ppc": 8, "cfl": 0.4, "end_time": %g},
    "fluid": {"bulk_modulus": %g, "jbar_psi": %g},
    "boundaries": [
      {"name": "floor", "type": "half_space", "point": [0, 0, %g], "normal": [0, 0, 1], "condition": "slip"},
      {"name": "x0", "type": "half_space", "point": [0, 0, 0], "normal": [1, 0, 0], "condition": "slip"},
      {"name": "x1", "type": "half_space", "point": [%g, 0, 0], "normal": [-1, 0, 0], "condition": "slip"},
      {"name": "y0", "type": "half_space", "point": [0, 0, 0], "normal": [0, 1, 0], "condition": "slip"},
      {"name": "y1", "type": "half_space", "point": [0, %g, 0], "normal": [0, -1, 0], "condition": "slip"}],
    "water": [{"lo": [0, 0, %g], "hi": [%g, %g, %g]}],
    "debris": {"density": %g, "bodies": [{"name": "D1", "size": [%g, %g, %g], "position": [%g, %g, %g]}]},
    "instruments": {"diagnostics_rate_hz": 50}
  })",
                -pad, -pad, -pad, L + pad, L + pad, z_floor + std::max(2 * depth, z_centre + size[2]) + pad, dx,
                end_time, bulk_modulus, psi, z_floor, L, L, z_floor, L, L, z_floor + depth, rho_b, size[0], size[1],
                size[2], L / 2, L / 2, z_floor + z_centre);
  return buf;
}

// The same with a cube of edge H in a soft fluid (K = 5e4 Pa).
inline std::string tank_scene(double L, double depth, double H, double rho_b, double z_centre, double dx, double end_time,
                              double psi = 0.0) {
  const double cube[3] = {H, H, H};
  return tank_scene(L, depth, cube, rho_b, z_centre, dx, end_time, psi, 5e4);
}

}  // namespace flume::test
