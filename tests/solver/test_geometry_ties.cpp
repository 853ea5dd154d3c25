// The boundaries' discrete decisions at a grid node (which faces hold it, whether and where it is mirrored) must
// not depend on the last bit of its coordinate. Scene walls mostly lie on grid lines or half cells, so nodes sit
// exactly on the rules' thresholds, and a coordinate rounded once differently (a fused multiply-add on a GPU,
// another compiler) moved water across the Waseda strip's quay unlike the CPU (docs/benchmarks.md). Each node
// near each wall of the shipped Waseda scenes is moved by one unit in the last place along each axis, both ways.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "solver/mpm/blocks_k.h"
#include "solver/mpm/boundaries.h"
#include "solver/mpm/node_k.h"
#include "solver/scene.h"

namespace {

using namespace flume;

template <int D>
struct Decision {
  int faces = 0;
  double n[2 * D][D] = {};
  mpm::GhostSearch<D> ghost;
  bool operator==(const Decision& o) const {
    if (faces != o.faces || ghost.axes != o.ghost.axes || ghost.ambiguous != o.ghost.ambiguous) return false;
    for (int f = 0; f < faces; ++f)
      for (int d = 0; d < D; ++d)
        if (n[f][d] != o.n[f][d]) return false;
    for (int d = 0; d < D; ++d)
      if (ghost.offset[d] != o.ghost.offset[d]) return false;
    return true;
  }
};

template <int D>
Decision<D> decide(const double* x, const mpm::Wall<D, double>& w, double dx) {
  Decision<D> out;
  out.faces = mpm::wall_faces<D>(x, w.box != 0, w.a, w.b, dx, out.n);
  if (!out.faces) return out;
  if (w.box)
    mpm::ghost_box<D>(x, w.a, w.b, dx, out.ghost.offset, out.ghost.axes, out.ghost.ambiguous);
  else
    mpm::ghost_half_space<D>(x, w.a, w.b, dx, out.ghost.offset, out.ghost.axes, out.ghost.ambiguous);
  return out;
}

struct Census {
  long pairs = 0, changed = 0;
  std::string first;
};

// Every node within three cells of each wall box (half-spaces: within three cells of the plane, inside the domain).
template <int D>
Census census(const std::string& scene_file, double dx_override) {
  const Scene scene = load_scene(std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/" + scene_file,
                                 {{"solver.dx", std::to_string(dx_override)}});
  const double dx = scene.solver.dx;
  double grid_lo[D];
  for (int d = 0; d < D; ++d) grid_lo[d] = scene.domain_lo[d] - mpm::kBlock * dx;
  Census c;
  for (const auto& w : mpm::scene_walls<D, double>(scene)) {
    if (w.bc == mpm::Bc::kSymmetry) continue;
    int lo[D], hi[D];
    for (int d = 0; d < D; ++d) {
      const double a = w.box ? w.a[d] : scene.domain_lo[d], b = w.box ? w.b[d] : scene.domain_hi[d];
      lo[d] = int(std::floor((std::max(a, scene.domain_lo[d]) - grid_lo[d]) / dx)) - 3;
      hi[d] = int(std::ceil((std::min(b, scene.domain_hi[d]) - grid_lo[d]) / dx)) + 3;
    }
    int i[D];
    for (int d = 0; d < D; ++d) i[d] = lo[d];
    while (true) {
      double x[D];
      for (int d = 0; d < D; ++d) x[d] = mpm::node_coordinate(grid_lo[d], i[d], dx);
      const Decision<D> at = decide<D>(x, w, dx);
      ++c.pairs;
      for (int d = 0; d < D; ++d)
        for (double toward : {-INFINITY, INFINITY}) {
          double moved[D];
          for (int e = 0; e < D; ++e) moved[e] = x[e];
          moved[d] = std::nextafter(x[d], toward);
          if (decide<D>(moved, w, dx) == at) continue;
          if (c.changed++ == 0) {
            c.first = "node";
            for (int e = 0; e < D; ++e) c.first += " " + std::to_string(x[e]);
            c.first += " moved along axis " + std::to_string(d);
          }
          d = D;  // count each node once
          break;
        }
      int axis = D - 1;  // the next node, last axis fastest
      while (axis >= 0 && ++i[axis] > hi[axis]) {
        i[axis] = lo[axis];
        --axis;
      }
      if (axis < 0) break;
    }
  }
  return c;
}

TEST(GeometryTies, TwoDimensionalBasinDecisionsIgnoreTheLastBit) {
  for (double dx : {0.01, 0.02, 0.025, 0.04}) {
    const Census c = census<2>("waseda_2d.json", dx);
    EXPECT_GT(c.pairs, 1000);
    EXPECT_EQ(c.changed, 0) << "dx " << dx << ": " << c.changed << " of " << c.pairs << " node-wall pairs; first "
                            << c.first;
  }
}

TEST(GeometryTies, StripDecisionsIgnoreTheLastBit) {
  for (double dx : {0.025, 0.05}) {
    const Census c = census<3>("waseda_strip.json", dx);
    EXPECT_GT(c.pairs, 1000);
    EXPECT_EQ(c.changed, 0) << "dx " << dx << ": " << c.changed << " of " << c.pairs << " node-wall pairs; first "
                            << c.first;
  }
}

// The whole basin, whole and halved: every wall kind the scenes generate (gate panel, quay, columns,
// reservoir and basin walls).
TEST(GeometryTies, WholeAndHalfBasinDecisionsIgnoreTheLastBit) {
  for (const char* file : {"waseda_3d.json", "waseda_3d_half.json"}) {
    const Census c = census<3>(file, 0.04);
    EXPECT_GT(c.pairs, 1000);
    EXPECT_EQ(c.changed, 0) << file << ": " << c.changed << " of " << c.pairs << " node-wall pairs; first " << c.first;
  }
}

}  // namespace
