// `flume report` (issue 7): the Ishigami campaign against its analytical Sobol' indices, mean and quantiles;
// failed runs listed and left out of the statistics; the debris analysis on positions with known answers;
// the command line; and the page rendered in headless Chromium.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "campaign_fixture.h"
#include "tests/common/run_command.h"
#include "report/geometry.h"
#include "report/report.h"


namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace flume::report;
using flume::store::RunOutcome;
using flume::store::RunStatus;

fs::path test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::temp_directory_path() / ("flume_report_" + std::to_string(getpid()) + "_" +
                                                    info->test_suite_name() + "_" + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}


void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
}

using Result = flume::test::CommandResult;
using flume::test::read_file;
Result run(const std::vector<std::string>& args, const fs::path& dir) { return flume::test::run_command(args, dir); }

const char* kPi = "3.141592653589793";

std::string ishigami_spec(const std::string& name, const std::string& design) {
  std::string x;
  for (const char* v : {"x1", "x2", "x3"})
    x += std::string(x.empty() ? "" : ", ") + R"({"path": ")" + v +
         R"(", "distribution": {"type": "uniform", "lower": -)" + kPi + R"(, "upper": )" + kPi + "}}";
  return R"({"name": ")" + name + R"(", "model": "ishigami", "parameters": [)" + x + R"(], "design": )" +
         design + R"(, "seed": 11})";
}

double ishigami(const std::vector<double>& x) {
  const double a = 7, b = 0.1;
  return std::sin(x[0]) + a * std::pow(std::sin(x[1]), 2) + b * std::pow(x[2], 4) * std::sin(x[0]);
}

// The Ishigami output's CDF by quadrature. Given x1 and x3, Y = c + a sin^2 x2 with
// c = sin x1 (1 + b x3^4), and P(sin^2 x2 <= t) = (2 / pi) asin(sqrt t) for x2 ~ U(-pi, pi); so
// F(y) = E[(2 / pi) asin(sqrt(clamp((y - c) / a, 0, 1)))] over (x1, x3), a midpoint rule on a 600^2 grid
// (error in F ~ 1e-5, far inside the intervals tested). Quantiles by bisection.
struct IshigamiCdf {
  std::vector<double> c;
  IshigamiCdf() {
    const double b = 0.1, pi = M_PI;
    const int m = 600;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        const double x1 = -pi + (i + 0.5) * 2 * pi / m, x3 = -pi + (j + 0.5) * 2 * pi / m;
        c.push_back(std::sin(x1) * (1 + b * std::pow(x3, 4)));
      }
  }
  double operator()(double y) const {
    double s = 0;
    for (double ci : c) s += (2 / M_PI) * std::asin(std::sqrt(std::clamp((y - ci) / 7.0, 0.0, 1.0)));
    return s / c.size();
  }
  double quantile(double p) const {
    double lo = -20, hi = 25;
    for (int k = 0; k < 45; ++k) {
      const double mid = 0.5 * (lo + hi);
      ((*this)(mid) < p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  double density(double y) const { return ((*this)(y + 0.05) - (*this)(y - 0.05)) / 0.1; }
};

ReportOptions options_for(const fs::path& db, const std::string& campaign, const fs::path& out) {
  ReportOptions o;
  o.db_file = db.string();
  o.campaign = campaign;
  o.out_dir = out.string();
  return o;
}

const MetricReport& metric(const Report& r, const std::string& name) {
  for (const auto& m : r.metrics)
    if (m.name == name) return m;
  throw std::runtime_error("no metric " + name);
}

}  // namespace

// Issue 7, point 1. Analytical values (Ishigami & Homma 1990; Sobol' & Levitan 1999), a = 7, b = 0.1:
// V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V13 = 8 b^2 pi^8 / 225, V3 = V12 = V23 = V123 = 0.
// Ten intervals are checked together, so each is asked at 1 - 0.05 / 10 = 99.5 % (--confidence 0.995):
// by Bonferroni all ten hold at once with probability >= 95 % whatever the seed. (At 95 % each, some seed
// misses one of the ten more often than not; the 95 % level of each method is tested alone in
// test_report_stats.) The seed is the spec's, 11, fixed before the first run.
TEST(ReportIshigami, SobolIndicesMeanAndQuantilesMatchAnalyticalWithinTheirIntervals) {
  const fs::path dir = test_dir();
  const std::size_t n_base = 2000;  // 10000 runs
  flume::test::make_campaign(
      (dir / "study.db").string(),
      ishigami_spec("ishigami", R"({"type": "saltelli", "samples": )" + std::to_string(n_base) + "}"),
      [](const std::vector<double>& x, std::int64_t) {
        return flume::test::ok_outcome({{"y", ishigami(x)}});
      });
  ReportOptions o = options_for(dir / "study.db", "ishigami", dir / "out");
  o.stats.confidence = 0.995;
  o.stats.bootstrap = 2000;  // 5 resamples beyond each 0.25 % tail
  const Report r = build_report(o);
  write_report(r);

  const double a = 7, b = 0.1, pi4 = std::pow(M_PI, 4), pi8 = std::pow(M_PI, 8);
  const double v1 = 0.5 * std::pow(1 + b * pi4 / 5, 2), v2 = a * a / 8, v13 = 8 * b * b * pi8 / 225;
  const double v = v1 + v2 + v13;
  const double s_first[3] = {v1 / v, v2 / v, 0.0}, s_total[3] = {(v1 + v13) / v, v2 / v, v13 / v};
  ASSERT_NEAR(v, a * a / 8 + b * pi4 / 5 + b * b * pi8 / 18 + 0.5, 1e-9);  // the textbook variance

  const MetricReport& y = metric(r, "y");
  ASSERT_TRUE(y.sobol.has_value()) << y.sensitivity_note;
  EXPECT_EQ(y.sobol->base_size, n_base);
  EXPECT_EQ(y.sobol->base_dropped, 0u);
  ASSERT_EQ(r.sensitivity_inputs, (std::vector<std::string>{"x1", "x2", "x3"}));
  for (int k = 0; k < 3; ++k) {
    const Estimate& s1 = y.sobol->first[k];
    const Estimate& st = y.sobol->total[k];
    std::printf("x%d: S = %.4f [%.4f, %.4f] (analytic %.4f)   ST = %.4f [%.4f, %.4f] (analytic %.4f)\n",
                k + 1, s1.value, s1.ci.lo, s1.ci.hi, s_first[k], st.value, st.ci.lo, st.ci.hi, s_total[k]);
    EXPECT_LE(s1.ci.lo, s_first[k]) << "S" << k + 1;
    EXPECT_GE(s1.ci.hi, s_first[k]) << "S" << k + 1;
    EXPECT_LE(st.ci.lo, s_total[k]) << "ST" << k + 1;
    EXPECT_GE(st.ci.hi, s_total[k]) << "ST" << k + 1;
    // Not vacuous: a fifth of the indices' range for S, two fifths for ST (a variance of products, wider).
    EXPECT_LT(s1.ci.hi - s1.ci.lo, 0.2) << "S" << k + 1;
    EXPECT_LT(st.ci.hi - st.ci.lo, 0.4) << "ST" << k + 1;
  }

  // Moments and quantiles on the A and B blocks: 2N independent runs.
  ASSERT_TRUE(y.summary.has_value());
  EXPECT_EQ(y.summary->n, 2 * n_base);
  const Estimate& mean = y.summary->mean;
  std::printf("mean = %.4f [%.4f, %.4f] (analytic 3.5)   std = %.4f [%.4f, %.4f] (analytic %.4f)\n",
              mean.value, mean.ci.lo, mean.ci.hi, y.summary->std.value, y.summary->std.ci.lo,
              y.summary->std.ci.hi, std::sqrt(v));
  EXPECT_LE(mean.ci.lo, a / 2);
  EXPECT_GE(mean.ci.hi, a / 2);
  // Widths as the theory of each interval has them: 2 z sigma / sqrt(n) for the mean, and for a quantile
  // 2 z sqrt(p (1 - p) / n) / f(q) (the order-statistic interval's asymptotic width), z at 99.5 %.
  const double z = 2.807033768343811, n_ab = 2.0 * n_base;
  EXPECT_NEAR(mean.ci.hi - mean.ci.lo, 2 * z * std::sqrt(v / n_ab), 0.05 * 2 * z * std::sqrt(v / n_ab));
  EXPECT_LE(y.summary->std.ci.lo, std::sqrt(v));
  EXPECT_GE(y.summary->std.ci.hi, std::sqrt(v));
  const IshigamiCdf cdf;
  for (const auto& q : y.summary->quantiles) {
    const double exact = cdf.quantile(q.p);
    std::printf("q%.2f = %.4f [%.4f, %.4f] (quadrature %.4f)\n", q.p, q.q.value, q.q.ci.lo, q.q.ci.hi, exact);
    EXPECT_FALSE(q.ci_open);
    EXPECT_LE(q.q.ci.lo, exact) << "p " << q.p;
    EXPECT_GE(q.q.ci.hi, exact) << "p " << q.p;
    const double width = 2 * z * std::sqrt(q.p * (1 - q.p) / n_ab) / cdf.density(exact);
    EXPECT_NEAR(q.q.ci.hi - q.q.ci.lo, width, 0.25 * width) << "p " << q.p;
  }

  // The same numbers reach summary.json and the page.
  const json j = json::parse(read_file(dir / "out" / "summary.json"));
  EXPECT_DOUBLE_EQ(j["metrics"]["y"]["sobol"]["x2"]["first"]["value"].get<double>(), y.sobol->first[1].value);
  EXPECT_EQ(j["runs"]["sample_ok"].get<int>(), static_cast<int>(2 * n_base));
  const std::string html = read_file(dir / "out" / "report.html");
  EXPECT_NE(html.find("Martinez"), std::string::npos);
  EXPECT_NE(html.find("rest on 4000 of 4000 runs"), std::string::npos);
}

// Rank correlations on a non-Saltelli design: on y = x + 10 y_in + 100 z (the test model) every input acts
// monotonically upwards. Spearman sees mostly z; PRCC, which takes the other inputs' (linear, in ranks)
// effect out, finds all three, in the order of their weights.
TEST(ReportSensitivity, RankCorrelationsOnAMonteCarloDesign) {
  const fs::path dir = test_dir();
  flume::test::make_campaign((dir / "study.db").string(),
                             R"({"name": "lin", "model": "test", "parameters": [
          {"path": "x", "distribution": {"type": "uniform", "lower": 0, "upper": 1}},
          {"path": "y", "distribution": {"type": "uniform", "lower": 0, "upper": 1}},
          {"path": "z", "distribution": {"type": "uniform", "lower": 0, "upper": 1}}],
          "design": {"type": "monte_carlo", "samples": 400}, "seed": 3})",
                             [](const std::vector<double>& x, std::int64_t) {
                               return flume::test::ok_outcome({{"y", x[0] + 10 * x[1] + 100 * x[2]}});
                             });
  ReportOptions o = options_for(dir / "study.db", "lin", dir / "out");
  o.stats.bootstrap = 200;
  const Report r = build_report(o);
  const MetricReport& y = metric(r, "y");
  ASSERT_TRUE(y.correlations.has_value()) << y.sensitivity_note;
  EXPECT_FALSE(y.sobol.has_value());
  const auto& c = *y.correlations;
  // Spearman: the share of each input in a sum of uniforms, near 0.01, 0.1, 0.995 for these weights.
  EXPECT_LT(std::abs(c.spearman[0].value), 0.15);
  EXPECT_GT(c.spearman[2].value, 0.97);
  EXPECT_GT(c.spearman[2].value, c.spearman[1].value);
  for (int k = 0; k < 3; ++k) {
    EXPECT_GT(c.prcc[k].ci.lo, 0.0) << "PRCC of input " << k << " is positive";
    EXPECT_LT(c.prcc[k].ci.lo, c.prcc[k].ci.hi);
  }
  EXPECT_LT(c.prcc[0].value, c.prcc[1].value);
  EXPECT_LT(c.prcc[1].value, c.prcc[2].value);
}

// Issue 7, point 3: failed, unstable and timed-out runs are listed with their messages and counted, and the
// statistics are those of the ok runs alone, saying how many.
TEST(ReportFailures, FailedRunsAreListedAndStatisticsRestOnTheOthers) {
  const fs::path dir = test_dir();
  std::vector<double> ok_values;
  flume::test::make_campaign((dir / "study.db").string(),
                             R"({"name": "flaky", "model": "test", "parameters": [
          {"path": "x", "distribution": {"type": "uniform", "lower": 0, "upper": 1}}],
          "design": {"type": "monte_carlo", "samples": 40}, "seed": 5})",
                             [&](const std::vector<double>& x, std::int64_t i) {
                               RunOutcome o;
                               if (i % 10 == 3) {
                                 o.status = RunStatus::kUnstable;
                                 o.message =
                                     "energy grew 40 % beyond the work of gravity at t = 1.2 s (run " +
                                     std::to_string(i) + ")";
                               } else if (i % 10 == 7) {
                                 o.status = RunStatus::kFailed;
                                 o.message = "killed by signal 11";
                               } else if (i == 20) {
                                 o.status = RunStatus::kTimeout;
                                 o.message = "time limit of 60 s reached";
                               } else {
                                 o = flume::test::ok_outcome({{"y", 100 * x[0]}});
                                 ok_values.push_back(100 * x[0]);
                               }
                               // A failed run's partial metric must not leak into the statistics.
                               if (o.status != RunStatus::kOk) o.metrics = {{"y", 1e6}};
                               return o;
                             });
  const Report r = build_report(options_for(dir / "study.db", "flaky", dir / "out"));
  write_report(r);
  ASSERT_EQ(ok_values.size(), 31u);
  EXPECT_EQ(r.counts.at(RunStatus::kOk), 31u);
  EXPECT_EQ(r.counts.at(RunStatus::kUnstable), 4u);
  EXPECT_EQ(r.counts.at(RunStatus::kFailed), 4u);
  EXPECT_EQ(r.counts.at(RunStatus::kTimeout), 1u);
  EXPECT_EQ(r.not_ok.size(), 9u);
  EXPECT_EQ(r.sample_ok, 31u);
  const MetricReport& y = metric(r, "y");
  ASSERT_TRUE(y.summary.has_value());
  EXPECT_EQ(y.summary->n, 31u);
  double mean = 0;
  for (double v : ok_values) mean += v / ok_values.size();
  EXPECT_NEAR(y.summary->mean.value, mean, 1e-9);
  EXPECT_LT(y.summary->max, 100.0);

  const std::string html = read_file(dir / "out" / "report.html");
  EXPECT_NE(html.find("The statistics rest on 31 of 40 runs"), std::string::npos);
  EXPECT_NE(html.find("9 of them did not end ok and are left out"), std::string::npos);
  EXPECT_NE(html.find("energy grew 40 % beyond the work of gravity at t = 1.2 s (run 13)"),
            std::string::npos);
  EXPECT_NE(html.find("killed by signal 11"), std::string::npos);
  EXPECT_NE(html.find("time limit of 60 s reached"), std::string::npos);
  const std::string csv = read_file(dir / "out" / "runs_not_ok.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 10);  // header + 9
  const json j = json::parse(read_file(dir / "out" / "summary.json"));
  EXPECT_EQ(j["runs"]["counts"]["unstable"].get<int>(), 4);
  EXPECT_EQ(j["metrics"]["y"]["n"].get<int>(), 31);
}

// In a Saltelli design a failed run removes its whole block row (pick-freeze needs all d + 2 runs of it).
TEST(ReportFailures, SaltelliDropsTheBlockRowsOfFailedRuns) {
  const fs::path dir = test_dir();
  const std::size_t n = 400;
  flume::test::make_campaign((dir / "study.db").string(),
                             ishigami_spec("ish-fail", R"({"type": "saltelli", "samples": 400})"),
                             [&](const std::vector<double>& x, std::int64_t i) {
                               // Base rows 5 and 17 fail in different blocks (A, and the x2 block).
                               if (i == 5 || i == static_cast<std::int64_t>(3 * n + 17)) {
                                 RunOutcome o;
                                 o.status = RunStatus::kFailed;
                                 o.message = "synthetic failure";
                                 return o;
                               }
                               return flume::test::ok_outcome({{"y", ishigami(x)}});
                             });
  const Report r = build_report(options_for(dir / "study.db", "ish-fail", dir / "out"));
  const MetricReport& y = metric(r, "y");
  ASSERT_TRUE(y.sobol.has_value()) << y.sensitivity_note;
  EXPECT_EQ(y.sobol->base_size, n - 2);
  EXPECT_EQ(y.sobol->base_dropped, 2u);
  EXPECT_NE(y.sensitivity_note.find("2 left out"), std::string::npos) << y.sensitivity_note;
  EXPECT_EQ(y.summary->n, 2 * n - 1);  // run 5 is in A; 3N + 17 is outside the A and B blocks
}

TEST(ReportGeometry, WasedaObstacleLayouts) {
  EXPECT_TRUE(obstacle_layout("0x0").empty());
  const auto one = obstacle_layout("5x1");
  ASSERT_EQ(one.size(), 5u);
  EXPECT_NEAR(one[0].x0, 5.11, 1e-12);
  EXPECT_NEAR(one[0].x1, 5.21, 1e-12);
  EXPECT_NEAR(0.5 * (one[2].y0 + one[2].y1), 2.0, 1e-12);  // centred across the 4 m basin
  EXPECT_NEAR(one[1].y0 - one[0].y0, 0.325, 1e-12);
  EXPECT_NEAR(one[0].y0, 2.0 - 2 * 0.325 - 0.05, 1e-12);
  const auto two = obstacle_layout("5x2");
  ASSERT_EQ(two.size(), 10u);
  EXPECT_NEAR(two[5].x0, 5.11 + 0.45, 1e-12);
  EXPECT_THROW(obstacle_layout("five"), std::invalid_argument);
}

namespace {

// Metrics of one run whose debris k sits at initial (4.7, yk), run-up (xr, yr) and rest (xs, ys).
std::vector<std::pair<std::string, double>> debris_run(const std::vector<std::array<double, 6>>& d) {
  std::vector<std::pair<std::string, double>> m;
  for (std::size_t k = 0; k < d.size(); ++k) {
    const std::string p = "D" + std::to_string(k + 1) + ".";
    const auto& [x0, y0, xr, yr, xs, ys] = d[k];
    m.push_back({p + "initial_x_m", x0});
    m.push_back({p + "initial_y_m", y0});
    m.push_back({p + "runup_x_m", xr});
    m.push_back({p + "runup_y_m", yr});
    m.push_back({p + "rest_x_m", xs});
    m.push_back({p + "rest_y_m", ys});
    m.push_back({p + "longitudinal_max_m", xr - x0});
    m.push_back({p + "dammed", 0.0});
  }
  return m;
}

}  // namespace

// Debris positions with known answers: 4 runs of 3 debris. Run i puts debris 1 at a run-up spreading angle
// of 10 + 10 i degrees (10, 20, 30, 40), so P(> 22.5 deg) = 2 / 4 and P(> Nistor 3.69 + 0.8 * 3 = 6.09) = 1.
TEST(ReportDebris, ProbabilitiesPresenceAndRunOutFromKnownPositions) {
  const fs::path dir = test_dir();
  flume::test::make_campaign(
      (dir / "study.db").string(),
      R"({"name": "deb", "model": "debris", "overrides": {"obstacles.layout": "5x2", "n_debris": 3},
          "parameters": [{"path": "friction", "distribution": {"type": "uniform", "lower": 0.2, "upper": 0.6}}],
          "design": {"type": "monte_carlo", "samples": 4}, "seed": 1})",
      [](const std::vector<double>&, std::int64_t i) {
        const double deg = (10.0 + 10.0 * i) * M_PI / 180, L = 2.0;
        auto m = debris_run({
            {4.7, 2.0, 4.7 + L, 2.0 + L * std::tan(deg), 6.0 + 0.5 * i, 2.1},  // the spreading one
            {4.7, 1.8, 6.7, 1.8, 6.0 + 0.5 * i, 1.8},                          // straight on
            {4.7, 2.2, 6.7, 2.2, 5.0, 2.2},                                    // always rests at x = 5
        });
        // All at rest at the end but in run 3, whose debris 2 still moves.
        for (int k = 1; k <= 3; ++k) m.push_back({"D" + std::to_string(k) + ".at_rest", i == 3 && k == 2 ? 0.0 : 1.0});
        return flume::test::ok_outcome(m);
      });
  ReportOptions o = options_for(dir / "study.db", "deb", dir / "out");
  o.cell_m = 0.25;
  const Report r = build_report(o);
  write_report(r);
  ASSERT_EQ(r.debris.groups.size(), 1u);
  const DebrisGroup& g = r.debris.groups[0];
  EXPECT_EQ(g.layout, "5x2");
  EXPECT_EQ(g.geometry.layout_source, "overrides");
  EXPECT_EQ(g.geometry.obstacles.size(), 10u);
  EXPECT_EQ(g.n_debris, 3);
  EXPECT_NEAR(g.apex_x, 4.7, 1e-12);
  EXPECT_NEAR(g.apex_y, 2.0, 1e-12);
  auto prob = [&](const std::string& start) {
    for (const auto& p : g.probabilities)
      if (p.what.rfind(start, 0) == 0) return p;
    throw std::runtime_error("no probability " + start);
  };
  const Probability naito = prob("P(a spreading angle at run-up > 22.5 deg");
  EXPECT_EQ(naito.count, 2u);
  EXPECT_EQ(naito.n, 4u);
  EXPECT_DOUBLE_EQ(naito.p.value, 0.5);
  EXPECT_NEAR(naito.p.ci.lo, 0.0676, 1e-3);  // Clopper-Pearson 2 / 4 at 95 %
  EXPECT_NEAR(naito.p.ci.hi, 0.9324, 1e-3);
  EXPECT_EQ(prob("P(a spreading angle at run-up > 6.09 deg").count, 4u);
  // Rest angles: debris 1 rests at lateral 0.1 m after 1.3 + 0.5 i m: atan(0.1 / 1.3) = 4.4 deg < 6.09.
  EXPECT_EQ(prob("P(a spreading angle at rest > 6.09 deg").count, 0u);
  // Eq. 58 for N = 3: 3.31 m; every median longitudinal displacement here is 2 m.
  EXPECT_EQ(prob("P(median longitudinal displacement > 3.31 m").count, 0u);
  const Probability moving = prob("P(a debris not at rest when the run ended");
  EXPECT_EQ(moving.count, 1u);
  EXPECT_EQ(moving.n, 4u);

  // Presence: the cell holding (5.0, 2.2) has a debris at rest in every run; the one at (6.0, 2.1) in run 0
  // only.
  const auto& p = g.presence;
  const std::size_t nx = p.x_edges.size() - 1;
  auto cell = [&](double x, double y) {
    const std::size_t i = std::upper_bound(p.x_edges.begin(), p.x_edges.end(), x) - p.x_edges.begin() - 1;
    const std::size_t j = std::upper_bound(p.y_edges.begin(), p.y_edges.end(), y) - p.y_edges.begin() - 1;
    return j * nx + i;
  };
  EXPECT_DOUBLE_EQ(p.rest[cell(5.0, 2.2)], 1.0);
  EXPECT_DOUBLE_EQ(p.rest[cell(6.0, 2.1)], 0.25);
  double total = 0;
  for (double v : p.rest) total += v;
  EXPECT_NEAR(total, 3.0, 1e-12);  // 3 debris in distinct cells in every run, each run weighing 1 / 4
  // Run-out of the farthest debris at rest: 6.0 + 0.5 i - 4.45.
  ASSERT_EQ(g.runout_rest.x.size(), 4u);
  EXPECT_NEAR(g.runout_rest.x.front(), 6.0 - 4.45, 1e-12);
  EXPECT_NEAR(g.runout_rest.x.back(), 7.5 - 4.45, 1e-12);
  // The derived per-run metric gets statistics of its own.
  EXPECT_NEAR(metric(r, "debris.runout_rest_max_m").summary->mean.value, 6.75 - 4.45, 1e-12);
  EXPECT_NEAR(metric(r, "debris.moving_count").summary->mean.value, 0.25, 1e-12);
  EXPECT_NE(read_file(dir / "out" / "debris_positions.csv").find("5x2,3,"), std::string::npos);
}

// The command line: bad input is one line naming the option, exit 2; a good call writes every file.
TEST(ReportCli, BadInputExitsTwoWithOneLineAndGoodInputWritesTheFiles) {
  const fs::path dir = test_dir();
  flume::test::make_campaign((dir / "study.db").string(),
                             ishigami_spec("small", R"({"type": "lhs", "samples": 30})"),
                             [](const std::vector<double>& x, std::int64_t) {
                               return flume::test::ok_outcome({{"y", ishigami(x)}});
                             });
  const std::string db = (dir / "study.db").string(), out = (dir / "out").string();
  struct Bad {
    std::vector<std::string> args;
    std::string names;
  };
  const std::vector<Bad> bad = {
      {{"--db", (dir / "nothing.db").string(), "--out", out}, "--db"},
      {{"--db", db, "--campaign", "nope", "--out", out}, "--campaign"},
      {{"--db", db, "--out", out, "--thresholds", "z=1"}, "--thresholds"},
      {{"--db", db, "--out", out, "--thresholds", "y=1,abc"}, "--thresholds"},
      {{"--db", db, "--out", out, "--confidence", "1.5"}, "--confidence"},
      {{"--db", db}, "--out"},
      {{"--db", db, "--out", out, "--colour", "red"}, "--colour"},
  };
  for (const auto& b : bad) {
    std::vector<std::string> args = {FLUME_EXE, "report"};
    args.insert(args.end(), b.args.begin(), b.args.end());
    const Result r = run(args, dir);
    EXPECT_EQ(r.rc, 2) << b.names << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(b.names), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "report.html"));
  const Result ok = run(
      {FLUME_EXE, "report", "--db", db, "--out", out, "--thresholds", "y=5,10", "--ci-width", "y=0.5"}, dir);
  ASSERT_EQ(ok.rc, 0) << ok.err;
  for (const char* f : {"report.html", "summary.json", "metrics.csv", "exceedance.csv", "sensitivity.csv",
                        "convergence.csv", "runs_not_ok.csv", "debris_positions.csv", "debris_presence.csv"})
    EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  const json j = json::parse(read_file(dir / "out" / "summary.json"));
  EXPECT_EQ(j["metrics"]["y"]["exceedance"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["metrics"]["y"]["convergence"]["target_width"].get<double>(), 0.5);
  EXPECT_TRUE(j["metrics"]["y"].contains("rank_correlations"));
  // Self-contained: nothing is fetched from anywhere.
  const std::string html = read_file(dir / "out" / "report.html");
  const std::regex external(R"re((src|href)\s*=\s*"?\s*(https?:|//|file:)|<link|@import|url\((?!#))re",
                            std::regex::icase);
  EXPECT_FALSE(std::regex_search(html, external));
  EXPECT_EQ(html.find("src="), std::string::npos);
}

namespace {

std::string find_chromium() {
  const char* path = std::getenv("PATH");
  std::stringstream ss(path ? path : "/usr/bin");
  std::string d;
  while (std::getline(ss, d, ':'))
    for (const char* name : {"chromium", "chromium-browser"})
      if (!d.empty() && access((fs::path(d) / name).c_str(), X_OK) == 0) return (fs::path(d) / name).string();
  return "";
}

std::vector<std::string> chromium_args(const std::string& exe, const fs::path& profile) {
  // As root in a sandboxed, offline machine: no sandbox, no background network, a fresh profile.
  return {exe,
          "--headless",
          "--no-sandbox",
          "--disable-gpu",
          "--disable-quic",
          "--no-first-run",
          "--disable-background-networking",
          "--disable-component-update",
          "--disable-sync",
          "--enable-logging=stderr",
          "--v=0",
          "--user-data-dir=" + profile.string()};
}

}  // namespace

// Issue 7, point 2: a debris campaign run end to end by `flume campaign run` (synthetic debris model) and
// `flume report`; headless Chromium renders the page: every section is there, each figure drew, and the
// page's inline script ran to its end without an error.
TEST(ReportRender, HeadlessChromiumDrawsEverySectionWithoutScriptErrors) {
  const std::string chromium = find_chromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium not installed (scripts/setup installs it)";
  const fs::path dir = test_dir();
  write_file(dir / "spec.json", R"({"name": "debris-render", "model": "debris",
  "overrides": {"obstacles.layout": "5x1", "n_debris": 6},
  "parameters": [{"path": "friction", "distribution": {"type": "uniform", "lower": 0.2, "upper": 0.6}},
                 {"path": "restitution", "distribution": {"type": "uniform", "lower": 0.1, "upper": 0.6}},
                 {"path": "wave_scale", "distribution": {"type": "normal", "mean": 1.0, "std": 0.1}}],
  "design": {"type": "lhs", "samples": 16}, "seed": 7})");
  const Result c = run({FLUME_EXE, "campaign", "run", (dir / "spec.json").string(), "--db",
                        (dir / "study.db").string(), "--workers", "2"},
                       dir);
  ASSERT_EQ(c.rc, 0) << c.err;
  const Result rep =
      run({FLUME_EXE, "report", "--db", (dir / "study.db").string(), "--campaign", "debris-render", "--out",
           (dir / "out").string(), "--thresholds", "debris.runout_rest_max_m=2,3"},
          dir);
  ASSERT_EQ(rep.rc, 0) << rep.err;
  const std::string url = "file://" + (dir / "out" / "report.html").string();

  auto args = chromium_args(chromium, dir / "profile");
  args.push_back("--dump-dom");
  args.push_back(url);
  const Result dom = run(args, dir);
  ASSERT_EQ(dom.rc, 0) << dom.err.substr(0, 2000);
  // The check script appends its verdict only if it ran to the end.
  const std::regex verdict(
      R"re(<p id="render-check" class="meta" data-status="(\w+)">render check: ([^<]*)</p>)re");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom.out, m, verdict)) << "the page's script did not run to its end";
  EXPECT_EQ(m[1].str(), "ok") << m[2].str();
  const std::string counts = m[2].str();
  // Per section "drawn/figures": every figure drew, and the figure-bearing sections have some.
  const std::regex part(R"((\w+):(\d+)/(\d+))");
  std::map<std::string, std::pair<int, int>> drawn;
  for (auto it = std::sregex_iterator(counts.begin(), counts.end(), part); it != std::sregex_iterator(); ++it)
    drawn[(*it)[1]] = {std::stoi((*it)[2]), std::stoi((*it)[3])};
  ASSERT_EQ(drawn.size(), 5u) << counts;
  for (const auto& [section, n] : drawn) EXPECT_EQ(n.first, n.second) << section << " in " << counts;
  EXPECT_GE(drawn["debris"].second, 4) << counts;  // map, presence maps, angles/displacement, run-out
  EXPECT_GE(drawn["metrics"].second, 5) << counts;
  EXPECT_GE(drawn["convergence"].second, 5) << counts;
  for (const char* text : {"Top-down apron", "Naito 22.5 deg", "Nistor eq. 59", "Nistor eq. 58",
                           "P(a debris at rest in the cell)", "Run-out past the quay wall", "Spearman",
                           "The statistics rest on 16 of 16 runs", "Synthetic debris model"})
    EXPECT_NE(dom.out.find(text), std::string::npos) << text;
  // No script error reached the console.
  EXPECT_EQ(dom.err.find("Uncaught"), std::string::npos) << dom.err.substr(0, 2000);

  args = chromium_args(chromium, dir / "profile");
  args.push_back("--window-size=1100,3000");
  args.push_back("--screenshot=" + (dir / "report.png").string());
  args.push_back(url);
  const Result shot = run(args, dir);
  ASSERT_EQ(shot.rc, 0) << shot.err.substr(0, 2000);
  ASSERT_TRUE(fs::exists(dir / "report.png"));
  EXPECT_GT(fs::file_size(dir / "report.png"), 50000u) << "a blank page would compress to almost nothing";
}

// `flume debris-paths`: a short coupled run of the Waseda strip (three containers, the reservoir still held)
// drawn top-down with its guidelines; the table names each debris and the eq. 58 comparison for N = 3.
TEST(DebrisPaths, DrawsARunsDebrisWithTheGuidelines) {
  const fs::path dir = test_dir();
  const Result r = run({FLUME_EXE, "run", std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/waseda_strip.json", "--out",
                        (dir / "strip").string(), "--set", "solver.end_time=0.1", "--threads", "1", "--quiet"},
                       dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const Result p =
      run({FLUME_EXE, "debris-paths", (dir / "strip").string(), "--out", (dir / "paths.svg").string()}, dir);
  ASSERT_EQ(p.rc, 0) << p.err;
  for (const char* want :
       {"waseda_strip, obstacles 0x0, 3 debris", "D1", "D2", "D3", "Nistor eq. 58 (3.58 - 0.09 N) 3.310 m",
        "speed_end_m_s  at_rest",
        // 0.1 s is shorter than the 1 s a debris must stay slower than 1 cm/s to count as at rest
        "3 of 3 not at rest at the end (slower than 0.01 m/s over the run's last 1 s)"})
    EXPECT_NE(p.out.find(want), std::string::npos) << want << " in\n" << p.out;
  const std::string svg = read_file(dir / "paths.svg");
  for (const char* want : {"Naito 22.5 deg", "Nistor eq. 59: 6.09 deg", "Nistor eq. 58: 3.31 m", "initial",
                           "end of run, still moving (crosses)"})
    EXPECT_NE(svg.find(want), std::string::npos) << want;
  EXPECT_EQ(svg.find("rest (diamonds)"), std::string::npos) << "none of the three is at rest after 0.1 s";

  // Bad input: a folder that is not a run, an option out of place; exit 2 and the file named.
  const Result missing =
      run({FLUME_EXE, "debris-paths", (dir / "nope").string(), "--out", (dir / "x.svg").string()}, dir);
  EXPECT_EQ(missing.rc, 2);
  EXPECT_NE(missing.err.find((dir / "nope" / "run.json").string()), std::string::npos) << missing.err;
  const Result misplaced = run({FLUME_EXE, "debris-paths", "--set", "obstacles.layout=5x2", (dir / "strip").string(),
                                "--out", (dir / "x.svg").string()},
                               dir);
  EXPECT_EQ(misplaced.rc, 2);
  const Result recorded = run({FLUME_EXE, "debris-paths", (dir / "strip").string(), "--set", "obstacles.layout=5x2",
                               "--out", (dir / "x.svg").string()},
                              dir);
  EXPECT_EQ(recorded.rc, 2) << "the run records its scene: a --set for it is refused";
  EXPECT_FALSE(fs::exists(dir / "x.svg"));
}
