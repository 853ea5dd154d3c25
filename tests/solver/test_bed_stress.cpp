// The bed stress of a rough half-space (`roughness_m`, mpm::bed_stress): tau = rho C_f |u_t| u_t with the
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

Scene sliding_floor(double roughness) {
  return parse_scene_text(R"({"name": "sliding_floor", "dimension": 2,
    "domain": {"lo": [-0.1, -0.1], "hi": [1.1, 0.3], "walls": "slip"},
    "solver": {"dx": 0.02, "ppc": 4, "precision": "double", "end_time": 0.02},
    "fluid": {"density": 1000, "bulk_modulus": 2.0e6},
    "water": [{"lo": [0.2, 0], "hi": [0.8, 0.1]}],
    "boundaries": [{"name": "floor", "type": "half_space", "point": [0, 0], "normal": [0, 1],
                    "condition": "slip", "velocity": [1.0, 0], "roughness_m": )" +
                              std::to_string(roughness) + "}]}",
                          "sliding_floor.json");
}

using Factory = std::function<std::unique_ptr<Simulation>(const Scene&)>;

double streamwise_momentum_after(const Factory& make, double roughness) {
  const Scene scene = sliding_floor(roughness);
  auto sim = make(scene);
  EXPECT_EQ(test::run_until(*sim, kTime), RunStatus::kOk) << sim->message();
  double linear[3], angular[3];
  sim->momentum(linear, angular);
  return linear[0];
}

void expect_wall_law_drag(const Factory& make) {
  const double ks = 0.001;
  const double cf = mpm::bed_drag_coefficient(ks, kDx);
  // The coefficient itself: kappa / ln(z / z0) with z = 0.01 m, z0 = 1/30 mm.
  EXPECT_NEAR(cf, std::pow(0.41 / std::log(0.01 / (ks / 30)), 2), 1e-15);
  const double per_length = kRho * cf * kBedSpeed * kBedSpeed * kTime;  // momentum per metre of bed
  const double bed = kSlab + 3 * kDx;
  const double slowing = 2 * cf * kBedSpeed * kTime / (kDx / 2);  // 2 u / u_b at most
  const double wetted = streamwise_momentum_after(make, ks) / per_length;
  EXPECT_LE(wetted, bed * (1 + 1e-9)) << "momentum " << wetted * per_length << " kg m/s per m";
  EXPECT_GE(wetted, bed * (1 - slowing)) << "momentum " << wetted * per_length << " kg m/s per m";
  const double smooth = streamwise_momentum_after(make, 0.0);
  EXPECT_LT(std::fabs(smooth), 1e-3 * kSlab * per_length) << "a smooth sliding floor dragged the water";
}

TEST(BedStress, SlidingRoughFloorDragsTheWaterAtTheWallLawRate) {
  expect_wall_law_drag([](const Scene& s) { return make_simulation(s, {}); });
}

#ifdef FLUME_CUDA_EMULATION_AVAILABLE
TEST(BedStress, CudaEmulationDragsAsTheCpu) {
  expect_wall_law_drag([](const Scene& s) { return make_cuda_host_emulation(s, {}); });
}
#endif

TEST(BedStress, RoughnessIsABedsOnly) {
  auto with = [](const std::string& boundary) {
    return R"({"name": "r", "dimension": 2, "domain": {"lo": [0, 0], "hi": [1, 1]}, "solver": {"dx": 0.05, "end_time": 0.1},
      "water": [{"lo": [0.2, 0.2], "hi": [0.4, 0.4]}], "boundaries": [)" +
           boundary + "]}";
  };
  EXPECT_THROW(parse_scene_text(with(R"({"name": "b", "type": "box", "lo": [0.5, 0], "hi": [0.6, 0.1],
                                        "roughness_m": 0.001})"),
                                "box.json"),
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

}  // namespace
}  // namespace flume
