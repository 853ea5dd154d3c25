// Lobovsky et al. (2014), H = 0.3 m: water levels at the gauges H2-H4 of a 2D dam break (issue 2, item 3).
// The shipped scene scenes/dam_break/lobovsky_2014_2d.json is run at dx = H/30 and its gauges are compared
// with the records of Fig. 16 (t* = t sqrt(g/H), h/H), without a time shift, over 0 <= t* <= 5.5: the
// surge, its run-up on the end wall and the thin layer behind it, up to the return of the reflected bore
// to H4. After that the bore plunges and traps air; a gauge that reads the top of the connected water
// column (solver/instruments.h) and the experiment's level sensors no longer measure the same thing
// (docs/validation.md shows the full record).
//
// The pressure sensors 1-3 on the end wall (z = 3, 15, 30 mm; the scene's probes P1-P3): the impact's largest
// 5 ms mean before t* = 3 within 20 % of the record's (issue 30's criterion for pressure peaks; one
// repetition, Fig. 18's "peak event 5", 20 kHz). A 5 ms mean because the simulated wall pressure carries
// MPM's cell-crossing ripple at 100-300 Hz (docs/validation.md section 3b), which the record does not. Sensor
// 4 (80 mm) has no impact before t* = 3: its record only starts to rise there, so it is not scored. With the
// probes' reading of the particles' pressure (before 2026-12-07) P3's peak was 43 % low and P1's 21 % high;
// with half gravity the surge arrives after t* = 3 (both tests below).
//
// Error bound: the free surface is resolved to one particle spacing h = dx/2. We allow two of them, one for
// the flow's discretisation and one for the gauge's reading (it jumps by h as particles cross the top),
// i.e. RMS(h/H) <= dx/H = 1/30. The experiment's own scatter (the second acquisition series against the
// first: RMS 0.005-0.010 over the window) is small beside that. The bound is tight enough to matter: a
// gauge compared with its neighbour's record misses it by >= 0.044, a dry gauge by >= 0.12, and the same
// run with gravity at half strength (a slower surge) fails; the test checks all three.
//
//   FLUME_PLOT_DIR=DIR [FLUME_LOBOVSKY_DX=0.005] [FLUME_LOBOVSKY_TEND=8] [FLUME_SET="solver.method=sph"]
//   test_lobovsky
// writes DIR/lobovsky_2014.svg (simulation against the records, all four gauges) and the simulated gauges as
// DIR/lobovsky_2014_flume.csv; the environment variables change the resolution (m), the end time (t*) and
// any scene setting (test_util.h's env_overrides).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common/plot/figure.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

constexpr double kH = 0.3;      // initial water height (m)
constexpr double kGRec = 9.81;  // the records' t* = t sqrt(g/H) uses g = 9.81 (shared/validation README)
const char* const kGauges[4] = {"H1", "H2", "H3", "H4"};
// Record files: the curves TNL-SPH compares with (H1_2, H2_3, H3_3, H4_4), and a second acquisition series
// of H2-H4 (the `_4`/`_5` files, in shared/validation only) that measures the experiment's repeatability.
const char* const kRecord[4] = {"Fig16_WaterLevels_H1_2.dat", "Fig16_WaterLevels_H2_3.dat",
                                "Fig16_WaterLevels_H3_3.dat", "Fig16_WaterLevels_H4_4.dat"};
const char* const kRepeat[4] = {"", "Fig16_WaterLevels_H2_4.dat", "Fig16_WaterLevels_H3_4.dat",
                                "Fig16_WaterLevels_H4_5.dat"};
// Fig. 18's files hold sensors 1, 2, 3 in sensors_5, _4, _2 (each file's header names its sensor).
const char* const kProbes[3] = {"P1", "P2", "P3"};
const char* const kPressureRecord[3] = {"Fig18_peak_event_5_sensors_5.dat",
                                        "Fig18_peak_event_5_sensors_4.dat",
                                        "Fig18_peak_event_5_sensors_2.dat"};
constexpr double kImpactEnd = 3.0;     // t*: the impact's window ends; the run-up follows
constexpr double kPeakWindow = 0.005;  // s: the means whose largest is compared
constexpr double kPeakTolerance = 0.2;

double env_number(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atof(v) : fallback;
}

// A curve h/H against t*, linearly interpolated (held constant outside its range).
struct Curve {
  std::vector<double> t, h;
  double at(double x) const {
    if (x <= t.front()) return h.front();
    auto it = std::lower_bound(t.begin(), t.end(), x);
    if (it == t.end()) return h.back();
    const size_t i = it - t.begin();
    const double s = (x - t[i - 1]) / (t[i] - t[i - 1]);
    return h[i - 1] + s * (h[i] - h[i - 1]);
  }
};

// A Fig. 16 record: two numeric columns (whitespace or comma separated) after '#' or quoted header lines.
Curve read_record(const std::string& path) {
  Curve c;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == '"') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    double t, h;
    if (ss >> t >> h) {
      c.t.push_back(t);
      c.h.push_back(h);
    }
  }
  return c;
}

struct GaugeRun {
  Curve gauge[4];
  Curve pressure[3];  // p / (rho g H) at P1-P3 against t*
  double wall_s = 0;
  long steps = 0;
  size_t particles = 0;
};

// Runs the shipped scene at resolution dx up to t* = end_tstar, with extra scene overrides.
GaugeRun simulate(double dx, double end_tstar, std::vector<Override> sets = {}) {
  const double t_scale = std::sqrt(kGRec / kH);
  sets.push_back({"solver.dx", std::to_string(dx)});
  sets.push_back({"solver.end_time", std::to_string(end_tstar / t_scale)});
  sets.push_back({"instruments.snapshot_rate_hz", "0"});
  for (const auto& o : test::env_overrides()) sets.push_back(o);
  const Scene scene =
      load_scene(std::string(FLUME_SOURCE_DIR) + "/scenes/dam_break/lobovsky_2014_2d.json", sets);
  // One thread: results do not depend on the thread count, and on a shared 2-core CI machine OpenMP's
  // barriers under oversubscription cost milliseconds a step (measured 25x slower at 1800 particles).
  SimulationOptions options;
  options.threads = 1;
  auto sim = make_simulation(scene, options);
  const auto t0 = std::chrono::steady_clock::now();
  const RunStatus status = test::run_until(*sim, scene.solver.end_time + 1.0);
  GaugeRun r;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.steps = sim->steps();
  r.particles = sim->particle_count();
  EXPECT_EQ(status, RunStatus::kOk) << sim->message();
  for (int k = 0; k < 4; ++k) {
    const auto& ts = sim->record().gauges.at(kGauges[k]);
    for (size_t i = 0; i < ts.size(); ++i) {
      r.gauge[k].t.push_back(ts.time[i] * t_scale);
      r.gauge[k].h.push_back(ts.at(i) / kH);
    }
  }
  const double p_scale = scene.fluid.density * kGRec * kH;
  for (int k = 0; k < 3; ++k) {
    const auto& ts = sim->record().pressures.at(kProbes[k]);
    for (size_t i = 0; i < ts.size(); ++i) {
      r.pressure[k].t.push_back(ts.time[i] * t_scale);
      r.pressure[k].h.push_back(ts.at(i) / p_scale);
    }
  }
  return r;
}

// The largest mean over kPeakWindow-long windows (on multiples of it in t) of a curve against t*, before
// t_end*.
double largest_window_mean(const Curve& c, double t_end) {
  const double t_scale = std::sqrt(kGRec / kH);
  std::vector<double> sum, count;
  for (size_t i = 0; i < c.t.size(); ++i) {
    if (c.t[i] >= t_end) break;
    const size_t bin = static_cast<size_t>(c.t[i] / t_scale / kPeakWindow);
    if (bin >= sum.size()) sum.resize(bin + 1, 0.0), count.resize(bin + 1, 0.0);
    sum[bin] += c.h[i];
    count[bin] += 1;
  }
  double best = 0;
  for (size_t b = 0; b < sum.size(); ++b)
    if (count[b] > 0) best = std::max(best, sum[b] / count[b]);
  return best;
}

// RMS of (a - b) over the samples of `b` with t0 <= t* <= t1, `a` read at t* - shift.
double rms(const Curve& a, const Curve& b, double t0, double t1, double shift = 0) {
  double s = 0;
  int n = 0;
  for (size_t i = 0; i < b.t.size(); ++i) {
    if (b.t[i] < t0 || b.t[i] > t1) continue;
    const double e = a.at(b.t[i] - shift) - b.h[i];
    s += e * e;
    ++n;
  }
  return n ? std::sqrt(s / n) : NAN;
}

constexpr double kWindowEnd = 5.5;  // t*: the reflected bore returns to H4 after this

struct Records {
  Curve rec[4], rep[4];
};
Records load_records() {
  Records r;
  for (int k = 0; k < 4; ++k) {
    r.rec[k] = read_record(test::validation_file(std::string("lobovsky_2014/") + kRecord[k]));
    // The second acquisition series, for the experiment's own scatter (printed, not asserted).
    if (*kRepeat[k])
      r.rep[k] = read_record(test::validation_file(std::string("lobovsky_2014/") + kRepeat[k]));
  }
  return r;
}

void save_plot(const std::string& dir, const Records& r, const GaugeRun& run, double dx, double t_end) {
  plot::Figure fig(2, 2, 960, 640);
  char title[96];
  std::snprintf(title, sizeof title, "Lobovsky et al. (2014), H = 0.3 m: water levels (flume dx = H/%.0f)",
                kH / dx);
  fig.title(title);
  for (int k = 0; k < 4; ++k) {
    auto& ax = fig.axes(k / 2, k % 2).title(kGauges[k]).xlabel("t sqrt(g/H)").ylabel("h / H").xlim(0, t_end);
    ax.line(r.rec[k].t, r.rec[k].h, {.color = plot::Color{0, 0, 0}, .label = "experiment"});
    if (!r.rep[k].t.empty())
      ax.line(r.rep[k].t, r.rep[k].h,
              {.color = plot::Color{120, 120, 120},
               .dash = plot::Dash::kDashed,
               .label = "experiment, series 2"});
    ax.line(run.gauge[k].t, run.gauge[k].h, {.color = plot::palette(0), .label = "flume"});
    if (k > 0)
      ax.vline(kWindowEnd, {.color = plot::Color{200, 200, 200}, .dash = plot::Dash::kDotted, .label = ""});
    ax.legend(plot::Legend::kUpperLeft);
  }
  fig.save(dir + "/lobovsky_2014.svg");
  std::ofstream csv(dir + "/lobovsky_2014_flume.csv");
  csv << "# flume, scenes/dam_break/lobovsky_2014_2d.json at dx = " << dx << " m: t*, h/H at H1..H4\n";
  csv << "t_star,H1,H2,H3,H4\n";
  for (size_t i = 0; i < run.gauge[0].t.size(); ++i) {
    csv << run.gauge[0].t[i];
    for (int k = 0; k < 4; ++k) csv << "," << run.gauge[k].h[i];
    csv << "\n";
  }
}

TEST(Lobovsky2014, GaugesH2toH4MatchRecord) {
  const double dx = env_number("FLUME_LOBOVSKY_DX", kH / 30);
  const double bound = dx / kH;  // two particle spacings, in h/H (see the top of the file)
  const double t_end = std::max(kWindowEnd + 0.2, env_number("FLUME_LOBOVSKY_TEND", kWindowEnd + 0.2));
  const Records r = load_records();
  for (int k = 0; k < 4; ++k) ASSERT_GE(r.rec[k].t.size(), 100u) << kRecord[k] << " not found";
  const GaugeRun run = simulate(dx, t_end);
  std::printf("dx = H/%.0f: %zu particles, %ld steps, %.1f s; bound RMS(h/H) <= %.4f over 0 <= t* <= %.1f\n",
              kH / dx, run.particles, run.steps, run.wall_s, bound, kWindowEnd);
  for (int k = 1; k < 4; ++k) {
    const double e = rms(run.gauge[k], r.rec[k], 0, kWindowEnd);
    // Reported, not asserted: the best single shift (the simulated surge arrives early; the gate's lift).
    double best = 1e300, best_shift = 0;
    for (int s = -50; s <= 50; ++s) {
      const double v = rms(run.gauge[k], r.rec[k], 0, kWindowEnd, 0.01 * s);
      if (v < best) best = v, best_shift = 0.01 * s;
    }
    const double scatter = r.rep[k].t.empty() ? NAN : rms(r.rep[k], r.rec[k], 0, kWindowEnd);
    std::printf("%s (x = %s): RMS(h/H) = %.4f (best shift %+.2f: %.4f; experiment series 2 vs 1: %.4f)\n",
                kGauges[k], k == 1 ? "0.865" : (k == 2 ? "1.114" : "1.3625"), e, best_shift, best, scatter);
    EXPECT_LE(e, bound) << kGauges[k] << " against the record";
    // The bound discriminates: the neighbouring gauges' readings and a dry gauge miss this record.
    for (int j : {k - 1, k + 1}) {
      if (j < 1 || j > 3) continue;
      const double wrong = rms(run.gauge[j], r.rec[k], 0, kWindowEnd);
      EXPECT_GT(wrong, bound) << kGauges[j] << " reading compared with the " << kGauges[k] << " record";
    }
    const Curve dry{{0.0, 1.0}, {0.0, 0.0}};
    EXPECT_GT(rms(dry, r.rec[k], 0, kWindowEnd), bound) << "a dry gauge against " << kGauges[k];
  }
  for (int k = 0; k < 3; ++k) {
    const Curve rec = read_record(test::validation_file(std::string("lobovsky_2014/") + kPressureRecord[k]));
    ASSERT_GE(rec.t.size(), 1000u) << kPressureRecord[k] << " not found";
    const double sim = largest_window_mean(run.pressure[k], kImpactEnd);
    const double meas = largest_window_mean(rec, kImpactEnd);
    std::printf(
        "%s: impact peak (largest 5 ms mean, t* < 3) %.2f against the record's %.2f (p / rho g H): %+.0f "
        "%%\n",
        kProbes[k], sim, meas, 100 * (sim / meas - 1));
    EXPECT_NEAR(sim, meas, kPeakTolerance * meas) << kProbes[k] << " impact pressure against the record";
  }
  if (const char* dir = std::getenv("FLUME_PLOT_DIR")) save_plot(dir, r, run, dx, t_end);
}

// Wrong physics must fail the same comparison: with gravity at half strength the surge is slower by
// sqrt(2) (its speed scales with sqrt(g H)) and at least one gauge leaves the bound.
TEST(Lobovsky2014, HalfGravityFails) {
  const double dx = kH / 30;
  const Records r = load_records();
  const GaugeRun run = simulate(dx, kWindowEnd, {{"solver.gravity", "[0.0, -4.903325]"}});
  double worst = 0;
  for (int k = 1; k < 4; ++k) {
    const double e = rms(run.gauge[k], r.rec[k], 0, kWindowEnd);
    std::printf("g/2: %s RMS(h/H) = %.4f\n", kGauges[k], e);
    worst = std::max(worst, e);
  }
  EXPECT_GT(worst, dx / kH) << "half gravity passed the comparison: the bound does not test the physics";
  double worst_peak = 0;
  for (int k = 0; k < 3; ++k) {
    const Curve rec = read_record(test::validation_file(std::string("lobovsky_2014/") + kPressureRecord[k]));
    const double meas = largest_window_mean(rec, kImpactEnd);
    worst_peak = std::max(worst_peak, std::fabs(largest_window_mean(run.pressure[k], kImpactEnd) / meas - 1));
  }
  EXPECT_GT(worst_peak, kPeakTolerance) << "half gravity passed the impact pressures";
}

}  // namespace
}  // namespace flume
