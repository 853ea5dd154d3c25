// Thread-count independence (issue 2, item 8's last sentence). The OpenMP scatter is race-free and
// order-deterministic by design: each particle block scatters into its private tile, and each grid block
// gathers its neighbours' tiles in a fixed order, so no sum's order depends on the threads. The particle
// state and everything computed from it serially (gauges, probes, dt) must therefore be BITWISE identical
// with 1, 2 and 3 threads. Only the OpenMP reductions (energies in the diagnostics, the per-thread load
// impulses) may differ, and only by round-off of their double sums.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <string>

#include "solver/mpm/thread_shares.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

test::FinalState run(const Scene& scene, int threads) {
  SimulationOptions o;
  o.threads = threads;
  auto sim = make_simulation(scene, o);
  EXPECT_EQ(omp_get_max_threads(), threads);
  EXPECT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kOk) << sim->message();
  return test::final_state(*sim);
}

void compare(const Scene& scene) {
  const test::FinalState one = run(scene, 1);
  for (int threads : {2, 3}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    const test::FinalState many = run(scene, threads);
    EXPECT_EQ(many.steps, one.steps);
    // Bitwise.
    EXPECT_TRUE(many.xyz == one.xyz) << "positions differ";
    EXPECT_TRUE(many.vel == one.vel) << "velocities differ";
    EXPECT_TRUE(many.p == one.p) << "pressures differ";
    for (const auto& [name, ts] : one.record.gauges)
      EXPECT_TRUE(many.record.gauges.at(name).values == ts.values) << name;
    for (const auto& [name, ts] : one.record.probes) {
      // A dry probe reads NaN, which never compares equal: compare the bit patterns' meaning instead.
      const auto& other = many.record.probes.at(name).values;
      ASSERT_EQ(other.size(), ts.values.size());
      for (size_t i = 0; i < other.size(); ++i)
        EXPECT_TRUE(other[i] == ts.values[i] || (std::isnan(other[i]) && std::isnan(ts.values[i])))
            << name << " " << i;
    }
    // Pressure probes sum their particles in particle order whatever the thread count (solver/pressure_probes.h).
    for (const auto& [name, ts] : one.record.pressures) {
      EXPECT_GT(*std::max_element(ts.values.begin(), ts.values.end()), 0.0) << name << ": must be wet";
      EXPECT_TRUE(many.record.pressures.at(name).values == ts.values) << name;
    }
    EXPECT_TRUE(many.record.diagnostics.at("dt") == one.record.diagnostics.at("dt"));
    EXPECT_TRUE(many.record.diagnostics.at("max_speed") == one.record.diagnostics.at("max_speed"));
    // Round-off of double reductions: a few ulps of the largest value.
    for (const char* k : {"kinetic", "potential", "elastic", "total"}) {
      const double r = test::rel_diff(one.record.diagnostics.at(k), many.record.diagnostics.at(k));
      EXPECT_LT(r, 1e-12) << k;
    }
    for (const auto& [name, ts] : one.record.loads) {
      double peak = 0;
      for (double f : ts.values) peak = std::max(peak, std::fabs(f));
      EXPECT_GT(peak, 1.0) << name
                           << ": the water must load the boundary for the comparison to mean anything";
      const double r = test::rel_diff(ts.values, many.record.loads.at(name).values);
      std::printf("[ info ] %d threads: load '%s' (peak %.3g N) differs by %.2e relative\n", threads,
                  name.c_str(), peak, r);
      EXPECT_LT(r, 1e-12) << name;
    }
  }
  std::printf("[ info ] %zu particles, %ld steps: particle state bitwise identical with 1, 2 and 3 threads\n",
              one.xyz.size() / 3, one.steps);
}

Scene dam_break(const std::string& precision, double end_time) {
  return load_scene(
      std::string(FLUME_SOURCE_DIR) + "/scenes/dam_break/martin_moyce_2d.json",
      {{"solver.dx", "0.005"},
       {"solver.precision", precision},
       {"solver.end_time", std::to_string(end_time)},
       {"instruments.snapshot_rate_hz", "0"},
       {"instruments.probes", R"([{"name": "p1", "position": [0.05, 0.01]}])"},
       {"instruments.loads", R"([{"name": "back_load", "boundary": "back_wall", "rate_hz": 1000}])"},
       {"instruments.pressure_probes", R"([{"name": "toe", "position": [0.05, 0.0], "normal": [0, 1]},
                                           {"name": "back_p", "position": [0.0, 0.02], "normal": [1, 0]}])"}});
}

TEST(Threads, DamBreak2DDouble) { compare(dam_break("double", 0.1)); }
TEST(Threads, DamBreak2DFloat) { compare(dam_break("float", 0.1)); }

TEST(Threads, DamBreak3DFloat) {
  const std::string text = R"({"name": "dam3d", "dimension": 3,
    "domain": {"lo": [0.0, 0.0, 0.0], "hi": [0.6, 0.2, 0.3], "walls": "separate", "friction": 0.2},
    "solver": {"dx": 0.02, "ppc": 8, "precision": "float", "end_time": 0.15},
    "fluid": {"bulk_modulus": 2.0e6, "jbar_psi": 0.9},
    "water": [{"lo": [0.04, 0.04, 0.04], "hi": [0.2, 0.16, 0.2]}],
    "boundaries": [{"name": "column", "type": "box", "lo": [0.26, 0.08, 0.0], "hi": [0.3, 0.12, 0.3]}],
    "instruments": {"gauges": [{"name": "g", "position": [0.3, 0.1]}],
                    "loads": [{"name": "column", "boundary": "column"}]}
  })";
  compare(parse_scene_text(text, "dam3d.json"));
}

// The shares every stage hands the threads: contiguous, each block in exactly one, balanced by particles to
// within one block, and each share's grid blocks the keys from its first particle block's on.
TEST(ThreadShares, SplitCoversEveryBlockOnceBalancedByParticleCount) {
  // Particle blocks (keys 10, 20, ...) of 1 to 64 particles; grid blocks at every key from 5 to 205.
  std::vector<uint64_t> pkeys, gkeys;
  std::vector<uint32_t> pstart = {0};
  for (int b = 0; b < 19; ++b) {
    pkeys.push_back(10 * (b + 1));
    pstart.push_back(pstart.back() + 1 + (b * 37) % 64);
  }
  for (uint64_t k = 5; k <= 205; ++k) gkeys.push_back(k);
  const double particles = pstart.back();
  for (int shares : {1, 2, 3, 7, 19, 25}) {
    SCOPED_TRACE(std::to_string(shares) + " shares");
    mpm::ThreadShares t;
    t.split(pstart, pkeys, gkeys, shares);
    ASSERT_EQ(t.count(), shares);
    EXPECT_EQ(t.pfirst.front(), 0);
    EXPECT_EQ(t.pfirst.back(), static_cast<long>(pkeys.size()));
    EXPECT_EQ(t.gfirst.front(), 0);
    EXPECT_EQ(t.gfirst.back(), static_cast<long>(gkeys.size()));
    for (int s = 0; s < shares; ++s) {
      EXPECT_LE(t.pfirst[s], t.pfirst[s + 1]);
      EXPECT_LE(t.gfirst[s], t.gfirst[s + 1]);
      const double count = pstart[t.pfirst[s + 1]] - pstart[t.pfirst[s]];
      EXPECT_LE(std::fabs(count - particles / shares), 64.0) << "share " << s;
      if (s > 0 && t.pfirst[s] < static_cast<long>(pkeys.size()))  // its grid blocks start at its first key
        EXPECT_EQ(gkeys[t.gfirst[s]], pkeys[t.pfirst[s]]) << "share " << s;
    }
  }
}

}  // namespace
}  // namespace flume
