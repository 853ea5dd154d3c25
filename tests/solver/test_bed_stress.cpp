// The bed stress of a rough wall (`roughness_m`, mpm::bed_stress): tau = rho C_f |u_t| u_t with the
// log law's C_f = (kappa / ln(z / z0))^2, z = dx / 2, z0 = k_s / 30. A floor sliding at u_b under a slab of
// still water drags it along: while the water on the bed moves at u << u_b, the water's momentum grows at
// rho C_f u_b^2 per unit of bed the drag acts on, so after t it is rho C_f u_b^2 L t (per metre of width in
// 2D). The drag acts on the bed's row of nodes, dx of bed each, wherever the stencil (1.5 cells) reaches
// water: L is the slab's length and 1.5 cells beyond each end. It can only be less by the speed the bed layer
// picks up: at least half a cell of water above each bed node takes the stress, so u <= C_f u_b^2 t / (dx /
// 2) and the stress falls by at most 2 u / u_b. A smooth floor (roughness 0) sliding under the same water
// does no work on it.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "common/errors.h"
#include "solver/cuda/mpm_cuda.h"
#include "solver/mpm_kernels.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

constexpr double kDx = 0.02, kSlab = 0.6, kBedSpeed = 1.0, kTime = 0.02, kRho = 1000;

// The floor's top at `level` (m): a half-space, or a box below it (`box`) whose faces take the same law.
Scene sliding_floor(double roughness, double level = 0, bool box = false) {
  const std::string lv = std::to_string(level), ks = std::to_string(roughness);
  const std::string floor =
      box ? R"({"name": "floor", "type": "box", "lo": [-0.3, -0.3], "hi": [1.3, )" + lv + "]"
          : R"({"name": "floor", "type": "half_space", "point": [0, )" + lv + R"(], "normal": [0, 1])";
  return parse_scene_text(R"({"name": "sliding_floor", "dimension": 2,
    "domain": {"lo": [-0.1, -0.1], "hi": [1.1, 0.3], "walls": "slip"},
    "solver": {"dx": 0.02, "ppc": 4, "precision": "double", "end_time": 0.02},
    "fluid": {"density": 1000, "bulk_modulus": 2.0e6},
    "water": [{"lo": [0.2, )" +
                              lv + R"(], "hi": [0.8, )" + std::to_string(level + 0.1) + R"(]}],
    "boundaries": [)" + floor +
                              R"(, "condition": "slip", "velocity": [1.0, 0], "roughness_m": )" + ks + "}]}",
                          "sliding_floor.json");
}

using Factory = std::function<std::unique_ptr<Simulation>(const Scene&)>;

double streamwise_momentum_after(const Factory& make, double roughness, double level = 0, bool box = false) {
  const Scene scene = sliding_floor(roughness, level, box);
  auto sim = make(scene);
  EXPECT_EQ(test::run_until(*sim, kTime), RunStatus::kOk) << sim->message();
  double linear[3], angular[3];
  sim->momentum(linear, angular);
  return linear[0];
}

constexpr double kRoughness = 0.001;

// The momentum the drag gave the water against the wall law's bounds (the file's comment): the floor's top at
// `level`, as a half-space or a box.
void expect_wall_law_drag(const Factory& make, double level = 0, bool box = false) {
  const double cf = mpm::bed_drag_coefficient(kRoughness, kDx);
  const double per_length = kRho * cf * kBedSpeed * kBedSpeed * kTime;  // momentum per metre of bed
  const double bed = kSlab + 3 * kDx;
  const double slowing = 2 * cf * kBedSpeed * kTime / (kDx / 2);  // 2 u / u_b at most
  const double wetted = streamwise_momentum_after(make, kRoughness, level, box) / per_length;
  const std::string where =
      std::string(box ? "box" : "half-space") + " floor at " + std::to_string(level) + " m";
  // Between grid lines the ghost row under the bed row takes the bed layer's velocity (mpm::ghost_exchange),
  // which adds momentum of the order the bed layer's own speed takes off the stress; on a grid line the
  // ghosts lie a cell down, reflecting the layer above.
  const bool on_grid = std::fabs(level / kDx - std::round(level / kDx)) < 1e-9;
  EXPECT_LE(wetted, bed * (1 + (on_grid ? 1e-9 : slowing)))
      << where << ": momentum " << wetted * per_length << " kg m/s per m";
  EXPECT_GE(wetted, bed * (1 - slowing)) << where << ": momentum " << wetted * per_length << " kg m/s per m";
  const double smooth = streamwise_momentum_after(make, 0.0, level, box);
  EXPECT_LT(std::fabs(smooth), 1e-3 * kSlab * per_length)
      << where << ": a smooth sliding floor dragged the water";
}

void expect_wall_law_drag_on_grid(const Factory& make) {
  // The coefficient itself: kappa / ln(z / z0) with z = 0.01 m, z0 = 1/30 mm.
  EXPECT_NEAR(mpm::bed_drag_coefficient(kRoughness, kDx),
              std::pow(0.41 / std::log(0.01 / (kRoughness / 30)), 2), 1e-15);
  expect_wall_law_drag(make);
}

TEST(BedStress, SlidingRoughFloorDragsTheWaterAtTheWallLawRate) {
  expect_wall_law_drag_on_grid([](const Scene& s) { return make_simulation(s, {}); });
}

// A bed between grid lines (the quay's top at 0.255 m on a 0.02 or 0.03 m grid) drags as one on a grid line:
// its bed row is the first row of nodes that are no ghosts, in the water above the face where the face lies a
// quarter cell or more above a row. Before, the row was the nodes less than half a cell inside, so a face
// half a cell or more above a row had none and dragged nothing.
TEST(BedStress, AFloorBetweenGridLinesDragsAtTheSameRate) {
  for (double level : {0.005, 0.01, 0.015})
    expect_wall_law_drag([](const Scene& s) { return make_simulation(s, {}); }, level);
}

// A box's faces take the wall law as a half-space does (the generated quay and apron are boxes): its top
// slows the water as a half-space at the same level, on a grid line and between grid lines.
TEST(BedStress, ABoxFloorDragsAsAHalfSpaceFloor) {
  const Factory cpu = [](const Scene& s) { return make_simulation(s, {}); };
  for (double level : {0.0, 0.01, 0.015}) {
    expect_wall_law_drag(cpu, level, true);
    const double plane = streamwise_momentum_after(cpu, kRoughness, level, false);
    const double box = streamwise_momentum_after(cpu, kRoughness, level, true);
    EXPECT_NEAR(box, plane, 1e-9 * std::fabs(plane)) << "floor at " << level << " m";
  }
}

#ifdef FLUME_CUDA_EMULATION_AVAILABLE
TEST(BedStress, CudaEmulationDragsAsTheCpu) {
  const Factory emulated = [](const Scene& s) { return make_cuda_host_emulation(s, {}); };
  expect_wall_law_drag_on_grid(emulated);
  expect_wall_law_drag(emulated, 0.015, true);
}
#endif

TEST(BedStress, RoughnessIsCheckedAndMpmOnly) {
  auto with = [](const std::string& boundary) {
    return R"({"name": "r", "dimension": 2, "domain": {"lo": [0, 0], "hi": [1, 1]}, "solver": {"dx": 0.05, "end_time": 0.1},
      "water": [{"lo": [0.2, 0.2], "hi": [0.4, 0.4]}], "boundaries": [)" +
           boundary + "]}";
  };
  EXPECT_THROW(parse_scene_text(with(R"({"name": "b", "type": "box", "lo": [0.5, 0], "hi": [0.6, 0.1],
                                        "condition": "sticky", "roughness_m": 0.001})"),
                                "sticky.json"),
               InputError);
  EXPECT_THROW(parse_scene_text(with(R"({"name": "f", "type": "half_space", "point": [0, 0], "normal": [0, 1],
                                        "roughness_m": 0.5})"),
                                "range.json"),
               InputError);
  const Scene sph = parse_scene_text(with(R"({"name": "f", "type": "half_space", "point": [0, 0],
                                             "normal": [0, 1], "roughness_m": 0.001})"),
                                     "sph.json", {{"solver.method", "sph"}});
  EXPECT_THROW(make_simulation(sph, {}), InputError);
}

// The basin generator's beds: `basin.bed_roughness_m` reaches the floor and the quay (the apron's top), and
// nothing else; sticky walls refuse it.
TEST(BedStress, BasinBedRoughnessReachesTheFloorAndTheQuay) {
  const std::string file = std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/waseda_3d.json";
  const Scene scene = load_scene(file, {{"basin.bed_roughness_m", "0.0002"}});
  int rough = 0;
  for (const auto& b : scene.boundaries) {
    const bool bed = b.name == "floor" || b.name == "quay";
    EXPECT_EQ(b.roughness, bed ? 0.0002 : 0.0) << b.name;
    rough += bed;
  }
  EXPECT_EQ(rough, 2);
  for (const auto& b : load_scene(file).boundaries) EXPECT_EQ(b.roughness, 0.0) << b.name;
  EXPECT_THROW(load_scene(file, {{"basin.bed_roughness_m", "0.0002"}, {"basin.walls", "sticky"}}),
               InputError);
  EXPECT_THROW(load_scene(file, {{"basin.bed_roughness_m", "0.2"}}), InputError);
  // SPH has no bed stress, and says which field to change.
  const Scene sph = load_scene(file, {{"basin.bed_roughness_m", "0.0002"}, {"solver.method", "sph"}});
  try {
    make_simulation(sph, {});
    ADD_FAILURE() << "SPH took a bed roughness";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("basin.bed_roughness_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace flume
