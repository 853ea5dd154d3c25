// SPH's symmetry plane (solver/sph/mirror.h, issue 24): half of a symmetric dam break, with a symmetry plane on
// the midline, must move as the same half of the whole. The images reproduce every pair the whole flow has
// across the midline, term for term, so the two differ only by the order in which the sums are taken: in double
// precision, by round-off grown through the flow, which stays far below a particle spacing. Images that leave
// out the walls' (the floor cut at the plane) move the gauges by 4-13 % of a spacing (docs/sph.md). A gauge whose
// footprint reaches the plane counts the water's image beyond it (solver/instruments.h, gauge_image).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

const SimulationOptions kOneThread{Backend::kCpu, 1};

// Three beyond a gauge's footprint (1.5 cells) of the plane, one within it (at 0.98 m: the half's gauge counts
// the water's image across the plane; read as beside a wall, it was 2.3 mm off the whole's in 3D).
constexpr double kGaugeX[] = {0.2, 0.5, 0.85, 0.98};

std::string gauges(int dim) {
  std::string g;
  for (double x : kGaugeX)
    g += std::string(g.empty() ? "" : ", ") + R"({"name": "G)" + std::to_string(int(std::lround(100 * x))) +
         R"(", "position": [)" + std::to_string(x) + (dim == 3 ? ", 0.05" : "") + R"(], "rate_hz": 200})";
  return g;
}

// A column 0.6 m wide (x) and 0.4 m deep in a tank 2 m long, symmetric about x = 1 m; 3D adds a width of 0.1 m
// (y) between slip walls. `half`: the part x <= 1 m, with a symmetry plane at x = 1 m.
std::string dam_scene(int dim, bool half, double dx, double end_time) {
  auto v = [&](double x, double yy, double z) {
    return "[" + std::to_string(x) + (dim == 3 ? ", " + std::to_string(yy) : "") + ", " + std::to_string(z) + "]";
  };
  const double pad = 2 * dx, x_hi = half ? 1.0 : 2.0;
  std::string walls = R"({"name": "left", "type": "half_space", "point": )" + v(0, 0, 0) + R"(, "normal": )" +
                      v(1, 0, 0) + R"(, "condition": "slip"},
      {"name": "floor", "type": "half_space", "point": )" + v(0, 0, 0) + R"(, "normal": )" + v(0, 0, 1) +
                      R"(, "condition": "slip"})";
  if (dim == 3)
    walls += R"(, {"name": "side0", "type": "half_space", "point": )" + v(0, 0, 0) + R"(, "normal": )" +
             v(0, 1, 0) + R"(, "condition": "slip"},
      {"name": "side1", "type": "half_space", "point": )" + v(0, 0.1, 0) + R"(, "normal": )" + v(0, -1, 0) +
             R"(, "condition": "slip"})";
  walls += half ? R"(, {"name": "midline", "type": "half_space", "point": )" + v(1, 0, 0) + R"(, "normal": )" +
                      v(-1, 0, 0) + R"(, "condition": "symmetry"})"
                : R"(, {"name": "right", "type": "half_space", "point": )" + v(2, 0, 0) + R"(, "normal": )" +
                      v(-1, 0, 0) + R"(, "condition": "slip"})";
  return R"({"name": "sph_symmetric_dam", "dimension": )" + std::to_string(dim) + R"(,
    "domain": {"lo": )" + v(-pad, -pad, -pad) + R"(, "hi": )" + v(x_hi + pad, 0.1 + pad, 0.8) + R"(},
    "solver": {"method": "sph", "dx": )" + std::to_string(dx) + R"(, "ppc": )" + (dim == 2 ? "4" : "8") +
         R"(, "precision": "double", "end_time": )" + std::to_string(end_time) + R"(},
    "fluid": {"bulk_modulus": 2.0e5, "gamma": 7.0, "viscosity": 1.0e-3},
    "boundaries": [)" + walls + R"(],
    "water": [{"lo": )" + v(0.7, 0, 0) + R"(, "hi": )" + v(half ? 1.0 : 1.3, 0.1, 0.4) + R"(}],
    "instruments": {"diagnostics_rate_hz": 10, "gauges": [)" + gauges(dim) + "]}}";
}

// The lowest x of the water (its front running to the left wall).
double front(const Simulation& sim) {
  std::vector<double> xyz;
  sim.particle_positions(xyz);
  double lo = 1e300;
  for (size_t i = 0; i < xyz.size(); i += 3) lo = std::min(lo, xyz[i]);
  return lo;
}

void check_half_moves_as_whole(int dim, double dx, double end_time) {
  const Scene whole = parse_scene_text(dam_scene(dim, false, dx, end_time), "whole.json");
  const Scene half = parse_scene_text(dam_scene(dim, true, dx, end_time), "half.json");
  auto a = make_simulation(whole, kOneThread), b = make_simulation(half, kOneThread);
  ASSERT_EQ(test::run_until(*a, end_time + 1), RunStatus::kOk) << a->message();
  ASSERT_EQ(test::run_until(*b, end_time + 1), RunStatus::kOk) << b->message();
  ASSERT_EQ(2 * b->particle_count(), a->particle_count());
  const double spacing = dx / 2;  // two particles a cell along each axis
  // By the end the front has run most of the way to the left wall; the two agree far below a spacing.
  const double bound = 1e-3 * spacing;
  EXPECT_NEAR(front(*b), front(*a), bound);
  for (double x : kGaugeX) {
    const std::string name = "G" + std::to_string(int(std::lround(100 * x)));
    const TimeSeries& ga = a->record().gauges.at(name);
    const TimeSeries& gb = b->record().gauges.at(name);
    ASSERT_EQ(ga.size(), gb.size()) << name;
    double worst = 0;
    for (size_t i = 0; i < ga.size(); ++i) worst = std::max(worst, std::fabs(ga.at(i) - gb.at(i)));
    EXPECT_LT(worst, bound) << name << ": the half's depth differs from the whole's by up to " << worst << " m";
  }
}

TEST(SphSymmetry, HalfDamBreakMovesAsTheWhole2D) { check_half_moves_as_whole(2, 0.02, 0.4); }
TEST(SphSymmetry, HalfDamBreakMovesAsTheWhole3D) { check_half_moves_as_whole(3, 0.05, 0.2); }

}  // namespace
}  // namespace flume
