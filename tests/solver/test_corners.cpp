// A stiff 3D dam-break bore along a channel: its floor (separate) meets the side and back walls (slip) at
// concave edges, where the ghost nodes beyond two walls and those beside them reflect onto one mirror node
// each (mpm::ghost_pool_velocity). MPM with dissipative walls cannot gain energy, and nothing but gravity
// acts before the front reaches the end wall. When the ghosts of a shared mirror exchanged pairwise, the sum
// did work on the water every step: at K = 2e7 Pa a particle-scale mode grew along the floor's edges from
// 0.14 s on, and the energy audit stopped this run at 0.18 s (bore_container at 0.19 s: docs/tradeoff.md,
// "The debris scene").
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "solver/scene.h"
#include "solver/simulation.h"

namespace flume {
namespace {

// bore_container's flume without its containers, 0.09 m wide and 0.7 m long (its dx, CFL and float).
const char* kBore = R"({
  "name": "corner_bore", "dimension": 3,
  "domain": {"lo": [-0.1, -0.1, -0.1], "hi": [0.8, 0.19, 0.3], "walls": "slip"},
  "solver": {"dx": 0.015, "ppc": 8, "cfl": 0.4, "precision": "float", "end_time": 0.2},
  "fluid": {"bulk_modulus": 2e7, "jbar_psi": 0.0},
  "boundaries": [
    {"name": "floor", "type": "half_space", "point": [0, 0, 0], "normal": [0, 0, 1], "condition": "separate"},
    {"name": "back", "type": "half_space", "point": [0, 0, 0], "normal": [1, 0, 0], "condition": "slip"},
    {"name": "end", "type": "half_space", "point": [0.7, 0, 0], "normal": [-1, 0, 0], "condition": "slip"},
    {"name": "side0", "type": "half_space", "point": [0, 0, 0], "normal": [0, 1, 0], "condition": "slip"},
    {"name": "side1", "type": "half_space", "point": [0, 0.09, 0], "normal": [0, -1, 0], "condition": "slip"}],
  "water": [{"lo": [0, 0, 0], "hi": [0.2, 0.09, 0.2]}],
  "instruments": {"diagnostics_rate_hz": 50}
})";

// The front (about 2.6 m/s) is still short of the end wall at 0.2 s. Between records the total may rise by
// no more than round-off: 1e-4 of it, far below the audit's 1 % slack.
TEST(Corners, StiffBoreAlongTheFloorsEdgesGainsNoEnergy) {
  const Scene scene = parse_scene_text(kBore, "corner_bore");
  auto sim = make_simulation(scene, {});
  RunStatus status;
  while ((status = sim->step()) == RunStatus::kRunning) {
  }
  ASSERT_EQ(status, RunStatus::kOk) << sim->message();
  const std::vector<double>& total = sim->record().diagnostics.at("total");
  const std::vector<double>& time = sim->record().diagnostics.at("time");
  ASSERT_GE(total.size(), 10u);
  for (size_t k = 1; k < total.size(); ++k)
    EXPECT_LE(total[k], total[k - 1] + 1e-4 * total[0]) << "at t = " << time[k] << " s";
  std::printf("[ info ] total energy %.5f J at t = 0, %.5f J at t = %.3f s\n", total.front(), total.back(),
              time.back());
}

}  // namespace
}  // namespace flume
