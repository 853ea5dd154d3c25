// The trade-off study's own parts: error metrics on synthetic series and run metrics with a known answer,
// wildcards over metric names, a study's evaluation on synthetic run.json files in a store built without the
// engine (relative differences, wildcards, missing values, what is stored), the Pareto front, spec validation
// (errors name the file and the field), the campaign `list` design it runs through, and one small study end
// to end through `flume study tradeoff`, a variant scene file included.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "campaign_fixture.h"
#include "campaigns/engine.h"
#include "campaigns/spec.h"
#include "common/errors.h"
#include "study/compare.h"
#include "study/tradeoff.h"
#include "xml_check.h"

namespace flume::study {
namespace {

namespace fs = std::filesystem;
const double kPi = std::acos(-1.0);

Series sampled(double dt, double t1, double (*f)(double)) {
  Series s;
  for (int i = 0; i * dt <= t1 + 1e-12; ++i) {
    s.time.push_back(i * dt);
    s.value.push_back(f(i * dt));
  }
  return s;
}

// sin against sin shifted by a constant: the RMS of a constant offset is the offset, whatever the grids.
TEST(Compare, RmsOfAConstantOffsetIsTheOffset) {
  const Series ref = sampled(0.01, 2.0, [](double t) { return std::sin(2 * kPi * t); });
  // The run sampled on another grid; linear in t so that interpolation is exact.
  const Series sim = sampled(0.0037, 2.0, [](double t) { return 0.3 * t + 0.05; });
  const Series lin = sampled(0.01, 2.0, [](double t) { return 0.3 * t; });
  EXPECT_NEAR(rms_difference(sim, lin, 0.0, 2.0), 0.05, 1e-12);
  // sin(2 pi t) against 0 over whole periods: RMS = 1 / sqrt(2).
  const Series zero = sampled(0.003, 2.0, [](double) { return 0.0; });
  EXPECT_NEAR(rms_difference(zero, ref, 0.0, 2.0), 1.0 / std::sqrt(2.0), 1e-3);
  // The window: only [0.5, 1.0] of ref, and the run's span limits it too.
  EXPECT_NEAR(rms_difference(zero, ref, 0.5, 1.0), 1.0 / std::sqrt(2.0), 2e-2);
  EXPECT_TRUE(std::isnan(rms_difference(zero, ref, 3.0, 4.0)));
}

TEST(Compare, NaNSamplesAreLeftOut) {
  Series ref = sampled(0.1, 1.0, [](double) { return 1.0; });
  Series sim = sampled(0.1, 1.0, [](double) { return 1.5; });
  sim.value[3] = std::nan("");  // a dry gauge: no reading
  EXPECT_NEAR(rms_difference(sim, ref, 0, 1), 0.5, 1e-12);
  EXPECT_NEAR(peak_in(sim, 0, 1), 1.5, 0);
}

TEST(Compare, PeakAndArrival) {
  // A bump of height 0.2 at t = 1 on a dry apron 0.025 m above the datum.
  auto bump = [](double t) { return 0.025 + 0.2 * std::exp(-std::pow((t - 1.0) / 0.1, 2)); };
  const Series ref = sampled(0.001, 2.0, bump);
  const Series late =
      sampled(0.001, 2.0, [](double t) { return 0.025 + 0.1 * std::exp(-std::pow((t - 1.1) / 0.1, 2)); });
  const GaugeError e = compare_gauge("WG3", late, ref, 0.0, 2.0, 0.005);
  EXPECT_NEAR(e.ref_peak_m, 0.225, 1e-6);
  EXPECT_NEAR(e.peak_m, 0.125, 1e-6);
  EXPECT_NEAR(e.peak_rel, (0.125 - 0.225) / 0.225, 1e-6);
  // Arrival: 0.2 exp(-((t - 1) / 0.1)^2) = 0.005 -> t = 1 - 0.1 sqrt(ln 40); the late one: 0.1 -> ln 20, +
  // 0.1.
  EXPECT_NEAR(e.ref_arrival_s, 1.0 - 0.1 * std::sqrt(std::log(40.0)), 1e-3);
  EXPECT_NEAR(e.arrival_s, 1.1 - 0.1 * std::sqrt(std::log(20.0)), 1e-3);
  EXPECT_NEAR(e.arrival_diff_s, e.arrival_s - e.ref_arrival_s, 1e-12);
  // Never arriving: NaN, and so is the difference.
  const Series flat = sampled(0.01, 2.0, [](double) { return 0.025; });
  const GaugeError none = compare_gauge("WG3", flat, ref, 0.0, 2.0, 0.005);
  EXPECT_TRUE(std::isnan(none.arrival_s));
  EXPECT_TRUE(std::isnan(none.arrival_diff_s));
}

TEST(Pareto, FrontIsTheNonDominatedSet) {
  //            a    b    c    d    e     f (NaN error: a failed run)
  const std::vector<double> cost = {1, 2, 3, 4, 2, 0.5};
  const std::vector<double> err = {0.5, 0.3, 0.3, 0.1, 0.6, std::nan("")};
  const auto front = pareto_front(cost, err);
  // b dominates c (same error, cheaper) and e; a, b, d are on the front; f is never.
  EXPECT_EQ(front, (std::vector<bool>{true, true, false, true, false, false}));
  // Ties: two identical points do not dominate each other.
  EXPECT_EQ(pareto_front({1, 1}, {0.2, 0.2}), (std::vector<bool>{true, true}));
}

// Run metrics: |value - ref| / max(|ref|, scale), worked by hand.
TEST(Compare, MetricRelativeDifferenceIsAgainstTheLargerOfReferenceAndScale) {
  auto reading = [](double v) { return MetricReading{true, v}; };
  // |0.72 - 0.8| / 0.8 = 0.1: the scale (0.015 m) is below |ref| and does not count.
  MetricError e = compare_metric({"D1.longitudinal_max_m", 0.015}, reading(0.72), reading(0.8));
  EXPECT_NEAR(e.diff, -0.08, 1e-15);
  EXPECT_NEAR(e.rel, 0.1, 1e-15);
  // A lateral displacement of 5 mm against a scale of 15 mm: 6 mm off is 0.4, not 1.2.
  e = compare_metric({"D1.lateral_rest_m", 0.015}, reading(0.011), reading(0.005));
  EXPECT_NEAR(e.diff, 0.006, 1e-15);
  EXPECT_NEAR(e.rel, 0.4, 1e-14);
  // A negative reference: its magnitude.
  EXPECT_NEAR(compare_metric({"D1.spreading_rest_deg", 0}, reading(-4.0), reading(-5.0)).rel, 0.2, 1e-15);
  // Reference 0 and no scale: no relative difference, and the reason in words.
  e = compare_metric({"debris.mobilised_count", 0}, reading(1), reading(0));
  EXPECT_TRUE(std::isnan(e.rel));
  EXPECT_DOUBLE_EQ(e.diff, 1.0);
  EXPECT_EQ(metric_problem(e), "reference 0, scale 0");
  // Missing or not finite in the run, or in the reference.
  EXPECT_EQ(metric_problem(compare_metric({"m", 0}, MetricReading{}, reading(1))), "missing");
  EXPECT_EQ(metric_problem(compare_metric({"m", 0}, reading(NAN), reading(1))), "not finite");
  EXPECT_EQ(metric_problem(compare_metric({"m", 0}, reading(1), MetricReading{})), "reference missing");
  EXPECT_EQ(metric_problem(compare_metric({"m", 0}, reading(1), reading(INFINITY))), "reference not finite");
  EXPECT_TRUE(std::isnan(compare_metric({"m", 0}, reading(INFINITY), reading(1)).diff));
  EXPECT_EQ(metric_problem(compare_metric({"m", 0}, reading(2), reading(1))), "");
}

TEST(Compare, MeanMetricErrorLeavesOutWhatTheReferenceLacksAndRefusesARunThatLacksOne) {
  auto reading = [](double v) { return MetricReading{true, v}; };
  const MetricError a = compare_metric({"a", 0}, reading(1.1), reading(1.0));    // 0.1
  const MetricError b = compare_metric({"b", 0.5}, reading(0.3), reading(0.1));  // 0.2 / 0.5 = 0.4
  const MetricError no_ref = compare_metric({"c", 0}, reading(7), MetricReading{});
  const MetricError zero_ref = compare_metric({"d", 0}, reading(7), reading(0));
  EXPECT_NEAR(mean_metric_error({a, b}), 0.25, 1e-15);
  // What the reference does not define is left out of every run's mean alike.
  EXPECT_NEAR(mean_metric_error({a, no_ref, b, zero_ref}), 0.25, 1e-15);
  // A run that lacks a metric the reference has is not ranked on fewer terms.
  EXPECT_TRUE(std::isnan(mean_metric_error({a, compare_metric({"b", 0.5}, MetricReading{}, reading(0.1))})));
  EXPECT_TRUE(std::isnan(mean_metric_error({a, compare_metric({"b", 0.5}, reading(NAN), reading(0.1))})));
  EXPECT_TRUE(std::isnan(mean_metric_error({no_ref})));
  EXPECT_TRUE(std::isnan(mean_metric_error({})));
}

TEST(Compare, WildcardsStayInsideOneComponentOfTheName) {
  EXPECT_TRUE(wildcard_match("D*.rest_x_m", "D1.rest_x_m"));
  EXPECT_TRUE(wildcard_match("D*.rest_x_m", "D12.rest_x_m"));
  EXPECT_TRUE(wildcard_match("D*.rest_x_m", "D.rest_x_m"));
  EXPECT_FALSE(wildcard_match("D*.rest_x_m", "D1.a.rest_x_m"));
  EXPECT_FALSE(wildcard_match("D*.rest_x_m", "D1.rest_x_mm"));
  EXPECT_FALSE(wildcard_match("D*.rest_x_m", "E1.rest_x_m"));
  EXPECT_TRUE(wildcard_match("*.peak_force_n", "col3.peak_force_n"));
  EXPECT_TRUE(wildcard_match("D1.*_deg", "D1.spreading_rest_deg"));
  EXPECT_TRUE(wildcard_match("D*.*", "D2.dammed"));
  EXPECT_FALSE(wildcard_match("D*", "D2.dammed"));
  EXPECT_TRUE(wildcard_match("mass_kg", "mass_kg"));
  EXPECT_FALSE(wildcard_match("mass_kg", "mass_kgs"));
}

TEST(Compare, PatternsExpandAgainstTheReferenceNames) {
  const std::vector<std::string> ref = {"D1.lateral_rest_m", "D1.longitudinal_max_m", "D2.lateral_rest_m",
                                        "D2.longitudinal_max_m", "debris.mobilised_count"};
  std::vector<size_t> unmatched;
  const auto out = expand_metric_patterns({{"D*.longitudinal_max_m", 0.01},
                                           {"D*.lateral_rest_m", 0.02},
                                           {"D2.longitudinal_max_m", 0.5},  // already given: first scale wins
                                           {"D3.rest_x_m", 0},              // no `*`: kept, though absent
                                           {"Q*.x", 0}},                    // matches nothing
                                          ref, &unmatched);
  std::vector<std::string> names;
  std::vector<double> scales;
  for (const auto& m : out) names.push_back(m.name), scales.push_back(m.scale);
  EXPECT_EQ(names, (std::vector<std::string>{"D1.longitudinal_max_m", "D2.longitudinal_max_m",
                                             "D1.lateral_rest_m", "D2.lateral_rest_m", "D3.rest_x_m"}));
  EXPECT_EQ(scales, (std::vector<double>{0.01, 0.01, 0.02, 0.02, 0}));
  EXPECT_EQ(unmatched, (std::vector<size_t>{4}));
}

const std::string kSrc = FLUME_SOURCE_DIR;

std::string base_spec(const std::string& settings, const std::string& extra = "") {
  return R"({"name": "t", "scene": ")" + kSrc + R"(/scenes/waseda/waseda_2d.json",
    "overrides": {"solver.end_time": 0.2}, "settings": )" +
         settings + R"(, "reference": {"setting": "fine"})" + extra + "}";
}

void expect_error(const std::string& text, const std::string& field, const std::string& words) {
  try {
    parse_tradeoff_spec(text, "study.json", "");
    FAIL() << "accepted; expected an error at " << field;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "study.json");
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(TradeoffSpec, ErrorsNameTheFileTheFieldAndWhatIsAllowed) {
  const std::string two = R"([{"label": "fine", "solver.dx": 0.02}, {"label": "coarse", "solver.dx": 0.04}])";
  EXPECT_NO_THROW(parse_tradeoff_spec(base_spec(two), "study.json", ""));
  // A value out of the scene's range: the setting's path, and the range.
  expect_error(base_spec(R"([{"label": "fine", "solver.dx": 0.02}, {"label": "bad", "solver.cfl": -1}])"),
               "settings.1.solver.cfl", "must be in (0, 10]");
  // A path the scene does not have.
  expect_error(base_spec(R"([{"label": "fine", "solver.dx": 0.02}, {"label": "typo", "solver.dxx": 0.04}])"),
               "settings.1.solver.dxx", "unknown field");
  // A variant scene file that does not exist.
  expect_error(base_spec(R"([{"label": "fine", "solver.dx": 0.02}, {"label": "v", "scene": "nope.json"}])"),
               "settings.1.scene", "cannot open");
  // Labels: required, unique; the reference must be one of them.
  expect_error(base_spec(R"([{"label": "fine", "solver.dx": 0.02}, {"solver.dx": 0.04}])"),
               "settings.1.label", "is required");
  expect_error(base_spec(R"([{"label": "fine", "solver.dx": 0.02}, {"label": "fine", "solver.dx": 0.04}])"),
               "settings.1.label", "already the label");
  expect_error(R"({"name": "t", "scene": ")" + kSrc + R"(/scenes/waseda/waseda_2d.json", "settings": )" +
                   two + R"(, "reference": {"setting": "finest"}})",
               "reference.setting", "not the label");
  // Outputs: names the scene has, a window that makes sense.
  expect_error(base_spec(two, R"(, "outputs": {"gauges": ["WG9"]})"), "outputs.gauges.0",
               "WG1, WG2, WG3, WG4");
  expect_error(base_spec(two, R"(, "outputs": {"window_s": [2, 1]})"), "outputs.window_s", "0 <= t0 < t1");
  expect_error(base_spec(two, R"(, "outptus": {})"), "outptus", "unknown field");
  expect_error(base_spec(R"([{"label": "fine"}])"), "settings", "at least two");
}

TEST(TradeoffSpec, MetricsErrorsNameTheEntry) {
  const std::string two = R"([{"label": "fine", "solver.dx": 0.02}, {"label": "coarse", "solver.dx": 0.04}])";
  auto with = [&](const std::string& outputs) { return base_spec(two, R"(, "outputs": )" + outputs); };
  // Metrics alone (no gauge, no load cell) are a study; names, patterns and {name, scale} entries.
  const TradeoffSpec ok = parse_tradeoff_spec(
      with(
          R"({"gauges": [], "metrics": ["D*.longitudinal_max_m", {"name": "D1.lateral_rest_m", "scale": 0.015},
                                          {"name": "debris.mobilised_count"}]})"),
      "study.json", "");
  EXPECT_TRUE(ok.gauges.empty());
  ASSERT_EQ(ok.metrics.size(), 3u);
  EXPECT_EQ(ok.metrics[0].name, "D*.longitudinal_max_m");
  EXPECT_EQ(ok.metrics[0].scale, 0);
  EXPECT_EQ(ok.metrics[1].scale, 0.015);
  // Without metrics, gauges and loads, nothing is compared.
  expect_error(with(R"({"gauges": [], "metrics": []})"), "outputs", "no metric");
  expect_error(with(R"({"metrics": "D1.rest_x_m"})"), "outputs.metrics", "must be an array");
  expect_error(with(R"({"metrics": ["D1.rest_x_m", 3]})"), "outputs.metrics.1", "run.json metric name");
  expect_error(with(R"({"metrics": ["D1.rest_x_m", ""]})"), "outputs.metrics.1", "must not be empty");
  expect_error(with(R"({"metrics": [{"name": "D1.rest_x_m", "scale": -1}]})"), "outputs.metrics.0.scale",
               "number >= 0");
  expect_error(with(R"({"metrics": [{"name": "D1.rest_x_m", "scale": "1 cm"}]})"), "outputs.metrics.0.scale",
               "number >= 0");
  expect_error(with(R"({"metrics": ["a", {"name": "b", "sacle": 1}]})"), "outputs.metrics.1.sacle",
               "unknown field (known: name, scale)");
  expect_error(with(R"({"metrics": ["a", "b", {"scale": 1}]})"), "outputs.metrics.2.name", "is required");
  expect_error(with(R"({"metrics": ["D*.rest_x_m", "b", {"name": "D*.rest_x_m"}]})"),
               "outputs.metrics.2.name", "already outputs.metrics.0");
  // A measured record has gauges only.
  expect_error(R"({"name": "t", "scene": ")" + kSrc + R"(/scenes/waseda/waseda_2d.json", "settings": )" +
                   two +
                   R"(, "reference": {"records": "fine.csv"}, "outputs": {"metrics": ["D1.rest_x_m"]}})",
               "outputs.metrics", "no run metrics");
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A study's evaluation on a store built here (no engine, no solver): each setting's run.json written by hand
// with the debris metrics the solver would write, so every error below is known exactly.
class TradeoffMetrics : public ::testing::Test {
 protected:
  const fs::path dir = fs::path(FLUME_TEST_OUT) / "metrics";
  const std::string db = (dir / "s.sqlite").string();

  // settings: fine (the reference), coarse, lacking (D2.longitudinal_max_m missing), broken (a null value),
  // and failed (no result); the wall times make coarse the cheapest.
  TradeoffSpec make(const std::string& metrics) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    const TradeoffSpec spec =
        parse_tradeoff_spec(R"({"name": "m", "scene": ")" + kSrc + R"(/scenes/debris/bore_container.json",
          "settings": [{"label": "fine", "solver.dx": 0.015}, {"label": "coarse", "solver.dx": 0.03},
                       {"label": "lacking", "solver.dx": 0.025}, {"label": "broken", "solver.dx": 0.02},
                       {"label": "failed", "solver.dx": 0.04}],
          "reference": {"setting": "fine"}, "outputs": {"gauges": [], "metrics": )" +
                                metrics + "}}",
                            "study.json", "");
    const std::vector<double> wall = {100, 10, 20, 30, 1};
    const std::int64_t id =
        test::make_campaign(db, spec.campaign, [&](const std::vector<double>&, std::int64_t k) {
          store::RunOutcome o = test::ok_outcome({});
          if (k == 4) o.status = store::RunStatus::kUnstable;
          o.wall_s = wall[k];
          return o;
        });
    const char* metrics_json[5] = {
        R"("D1.longitudinal_max_m": 0.8, "D2.longitudinal_max_m": 0.6, "D1.lateral_rest_m": 0.005,
           "D2.lateral_rest_m": 0.0, "debris.mobilised_count": 2, "mass_kg": 18.0)",
        R"("D1.longitudinal_max_m": 0.72, "D2.longitudinal_max_m": 0.66, "D1.lateral_rest_m": 0.011,
           "D2.lateral_rest_m": 0.002, "debris.mobilised_count": 2, "mass_kg": 18.0)",
        R"("D1.longitudinal_max_m": 0.76, "D1.lateral_rest_m": 0.005, "D2.lateral_rest_m": 0.0,
           "debris.mobilised_count": 2)",
        R"("D1.longitudinal_max_m": null, "D2.longitudinal_max_m": 0.6, "D1.lateral_rest_m": 0.005,
           "D2.lateral_rest_m": 0.0, "debris.mobilised_count": 2)",
        R"("D1.longitudinal_max_m": 9)"};
    store::CampaignStore s(db);
    const auto planned = campaigns::plan_runs(spec.campaign);
    for (size_t k = 0; k < planned.size(); ++k) {
      const fs::path run = dir / ("run-" + std::to_string(k));
      fs::create_directories(run);
      std::ofstream(run / "run.json") << R"({"status": "ok", "cost": {"steps": 100, "particles": 1000},
                                             "metrics": {)"
                                      << metrics_json[k] << "}}";
      s.set_run_dir(s.find_run(id, planned[k].param_hash)->id, run.string());
    }
    return spec;
  }
};

TEST_F(TradeoffMetrics, RelativeErrorsWildcardsAndMissingValues) {
  const TradeoffSpec spec = make(
      R"(["D*.longitudinal_max_m", {"name": "D*.lateral_rest_m", "scale": 0.015}, "debris.mobilised_count"])");
  const TradeoffResult result = evaluate_tradeoff(spec, db);
  // The wildcards, expanded against the reference's names (mass_kg is not asked for).
  std::vector<std::string> names;
  for (const auto& m : result.metrics) names.push_back(m.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"D1.longitudinal_max_m", "D2.longitudinal_max_m", "D1.lateral_rest_m",
                                      "D2.lateral_rest_m", "debris.mobilised_count"}));
  ASSERT_EQ(result.rows.size(), 5u);
  const SettingResult &fine = result.rows[0], &coarse = result.rows[1], &lacking = result.rows[2],
                      &broken = result.rows[3], &failed = result.rows[4];
  // coarse: 0.08 / 0.8, 0.06 / 0.6, 0.006 / max(0.005, 0.015), 0.002 / max(0, 0.015), 0 / 2.
  ASSERT_EQ(coarse.metrics.size(), 5u);
  const double rel[5] = {0.1, 0.1, 0.4, 0.002 / 0.015, 0};
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(coarse.metrics[i].rel, rel[i], 1e-12) << names[i];
  EXPECT_NEAR(coarse.metrics[0].diff, -0.08, 1e-12);
  EXPECT_NEAR(coarse.metrics[0].ref.value, 0.8, 0);
  EXPECT_NEAR(coarse.error[kMetric], (0.1 + 0.1 + 0.4 + 0.002 / 0.015) / 5, 1e-12);
  EXPECT_EQ(fine.error[kMetric], 0);
  // A missing metric and a null one: reported, and the run gets no aggregate (so it is off the front).
  EXPECT_EQ(metric_problem(lacking.metrics[1]), "missing");
  EXPECT_NEAR(lacking.metrics[0].rel, 0.05, 1e-12);
  EXPECT_TRUE(std::isnan(lacking.error[kMetric]));
  EXPECT_EQ(metric_problem(broken.metrics[0]), "not finite");
  EXPECT_TRUE(std::isnan(broken.error[kMetric]));
  EXPECT_TRUE(failed.metrics.empty());
  EXPECT_TRUE(std::isnan(failed.error[kMetric]));
  EXPECT_TRUE(coarse.pareto[kMetric]);
  EXPECT_FALSE(lacking.pareto[kMetric] || broken.pareto[kMetric] || failed.pareto[kMetric] ||
               fine.pareto[kMetric]);
  // No gauges: the gauge errors are not there, not zero.
  EXPECT_TRUE(std::isnan(coarse.error[kRms]));

  // The table says what is missing, the CSV has the columns and no NaN.
  const std::string md = tradeoff_markdown(spec, result);
  EXPECT_NE(md.find("| fine (reference) | solver.dx=0.015 | ok | 100.0 | 1e+05 | - | - | - | - | 0 |  |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| lacking |"), std::string::npos) << md;
  EXPECT_NE(md.find("| missing |"), std::string::npos) << md;
  EXPECT_NE(md.find("| not finite |"), std::string::npos) << md;
  EXPECT_NE(md.find("0.72 / -0.08 / 10.0 |"), std::string::npos) << md;
  write_tradeoff(spec, result, (dir / "out").string());
  const std::string csv = slurp(dir / "out" / "tradeoff.csv");
  EXPECT_NE(csv.find("error_metric"), std::string::npos) << csv;
  EXPECT_NE(csv.find("D1.lateral_rest_m.rel"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\"missing\""), std::string::npos) << csv;
  EXPECT_EQ(csv.find("nan"), std::string::npos) << csv;
  const std::string svg = slurp(dir / "out" / "tradeoff.svg");
  EXPECT_EQ(plot::test::check_xml(svg).error, "") << "tradeoff.svg is not well-formed XML";
  EXPECT_NE(svg.find("max(|ref.|, scale)"), std::string::npos);
  EXPECT_EQ(svg.find("RMS error"), std::string::npos) << "a panel for gauges the study does not have";

  // Stored: the aggregate and each metric's relative difference, and no NaN where a metric was missing.
  store_errors(result, db);
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &h), SQLITE_OK);
  auto metric = [&](const std::string& label, const std::string& name) {
    sqlite3_stmt* st = nullptr;
    const std::string sql =
        "SELECT m.value FROM metrics m JOIN runs r ON r.id = m.run WHERE r.run_dir LIKE '%/run-" +
        std::to_string(std::find_if(result.rows.begin(), result.rows.end(),
                                    [&](const SettingResult& r) { return r.label == label; }) -
                       result.rows.begin()) +
        "' AND m.name = '" + name + "'";
    sqlite3_prepare_v2(h, sql.c_str(), -1, &st, nullptr);
    const double v = sqlite3_step(st) == SQLITE_ROW && sqlite3_column_type(st, 0) != SQLITE_NULL
                         ? sqlite3_column_double(st, 0)
                         : std::nan("");
    sqlite3_finalize(st);
    return v;
  };
  EXPECT_NEAR(metric("coarse", "error.metric"), coarse.error[kMetric], 1e-12);
  EXPECT_NEAR(metric("coarse", "error.D1.lateral_rest_m.rel"), 0.4, 1e-12);
  EXPECT_NEAR(metric("coarse", "error.D1.lateral_rest_m.diff"), 0.006, 1e-12);
  EXPECT_EQ(metric("coarse", "pareto.metric"), 1);
  EXPECT_EQ(metric("fine", "error.metric"), 0);
  EXPECT_TRUE(std::isnan(metric("lacking", "error.metric")));
  // No gauges: no gauge errors stored, not even the reference's 0.
  EXPECT_TRUE(std::isnan(metric("fine", "error.rms")));
  EXPECT_TRUE(std::isnan(metric("coarse", "pareto.arrival")));
  EXPECT_TRUE(std::isnan(metric("lacking", "error.D2.longitudinal_max_m.rel")));
  EXPECT_NEAR(metric("lacking", "error.D1.longitudinal_max_m.rel"), 0.05, 1e-12);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(h, "SELECT count(*) FROM metrics WHERE value IS NULL OR value != value", -1, &st,
                     nullptr);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(st, 0), 0);
  sqlite3_finalize(st);
  sqlite3_close(h);
}

TEST_F(TradeoffMetrics, AReferenceZeroWithoutScaleIsLeftOutAndAWildcardMatchingNothingIsNamed) {
  // D2.lateral_rest_m is 0 in the reference: without a scale it has no relative difference and is left out
  // of the mean, which is then over the other metric only.
  TradeoffResult r = evaluate_tradeoff(make(R"(["D1.longitudinal_max_m", "D2.lateral_rest_m"])"), db);
  EXPECT_EQ(metric_problem(r.rows[1].metrics[1]), "reference 0, scale 0");
  EXPECT_NEAR(r.rows[1].error[kMetric], 0.1, 1e-12);
  // A name without `*` that the reference lacks: every row says so, nothing is ranked on it.
  r = evaluate_tradeoff(make(R"(["D1.longitudinal_max_m", "D7.rest_x_m"])"), db);
  EXPECT_EQ(metric_problem(r.rows[1].metrics[1]), "reference missing");
  EXPECT_NEAR(r.rows[1].error[kMetric], 0.1, 1e-12);
  // A pattern that matches none of the reference's names is a typo: the entry and what there is.
  try {
    evaluate_tradeoff(make(R"(["D1.longitudinal_max_m", "d*.rest_x_m"])"), db);
    FAIL() << "accepted a pattern that matches nothing";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "outputs.metrics.1");
    EXPECT_NE(e.problem().find("D1.lateral_rest_m"), std::string::npos) << e.what();
  }
}

// The specs the docs tell people to run stay valid as the scenes and the spec format change.
TEST(TradeoffSpec, ShippedSpecsParse) {
  for (const char* file : {"/scenes/studies/tradeoff_waseda_2d.json", "/scenes/studies/tradeoff_waseda_2d_stiffness.json",
                           "/scenes/studies/tradeoff_debris.json", "/scenes/studies/waseda_half_vs_full.json",
                           "/scenes/studies/waseda_half_vs_full_dx004.json"})
    EXPECT_NO_THROW(load_tradeoff_spec(kSrc + file)) << file;
  const TradeoffSpec debris = load_tradeoff_spec(kSrc + "/scenes/studies/tradeoff_debris.json");
  EXPECT_EQ(debris.labels.at(*debris.reference_setting), "dx 0.0075");
  EXPECT_EQ(debris.gauges, (std::vector<std::string>{"G1"}));
  EXPECT_EQ(debris.metrics.size(), 6u);
}

TEST(ListDesign, PointsBecomeChoiceParametersAndAbsentPathsKeepTheScene) {
  const std::string text = R"({"name": "l", "scene": ")" + kSrc + R"(/scenes/waseda/waseda_2d.json",
    "overrides": {"solver.end_time": 0.1},
    "design": {"type": "list", "points": [
      {"label": "a", "solver.dx": 0.04},
      {"label": "b", "solver.dx": 0.02, "solver.precision": "double"},
      {"label": "c", "scene": ")" +
                           kSrc + R"(/scenes/waseda/waseda_3d_half.json", "solver.dx": 0.04}]}})";
  const campaigns::CampaignSpec spec = campaigns::parse_campaign_spec(text, "list.json", "");
  ASSERT_TRUE(spec.listed);
  ASSERT_EQ(spec.parameters.size(), 3u);  // solver.dx, solver.precision, scene (in order of appearance)
  EXPECT_EQ(spec.point_labels, (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_NE(spec.point_scenes[2].find("waseda_3d_half.json"), std::string::npos);
  const auto argv_a = campaigns::run_command(spec, 0, "flume", "out");
  const auto argv_c = campaigns::run_command(spec, 2, "flume", "out");
  auto joined = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += x + " ";
    return s;
  };
  EXPECT_NE(joined(argv_a).find("--set solver.dx=0.04"), std::string::npos) << joined(argv_a);
  EXPECT_EQ(joined(argv_a).find("precision"), std::string::npos) << joined(argv_a);  // left to the scene
  EXPECT_NE(argv_c[2].find("waseda_3d_half.json"), std::string::npos) << joined(argv_c);
  EXPECT_EQ(joined(argv_c).find("--set scene="), std::string::npos) << joined(argv_c);
  // Distinct points, distinct hashes; the same point twice would share one.
  const auto planned = campaigns::plan_runs(spec);
  EXPECT_NE(planned[0].param_hash, planned[1].param_hash);
  EXPECT_NE(planned[0].param_hash, planned[2].param_hash);
  EXPECT_EQ(planned[0].params_json, R"({"solver.dx":0.04})");
}

// End to end, 0.3 s on coarse grids (a few seconds): three 2D settings and the 3D half-basin as a variant
// file.
TEST(TradeoffCli, RunsResumesAndWritesTableCsvAndPlot) {
  const fs::path dir = fs::path(FLUME_TEST_OUT) / "cli";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string spec = R"({"name": "mini", "scene": ")" + kSrc + R"(/scenes/waseda/waseda_2d.json",
    "overrides": {"solver.end_time": 0.3, "reservoir.forcing.t99_s": 0.1},
    "settings": [{"label": "fine", "solver.dx": 0.03}, {"label": "coarse", "solver.dx": 0.05},
                 {"label": "coarse cfl 0.8", "solver.dx": 0.05, "solver.cfl": 0.8},
                 {"label": "3D half", "scene": ")" +
                           kSrc + R"(/scenes/waseda/waseda_3d_half.json", "solver.dx": 0.1}],
    "reference": {"setting": "fine"}, "outputs": {"gauges": ["WG1", "WG2"], "window_s": [0, 0.3]},
    "run": {"time_limit_s": 120, "threads": 1}})";
  std::ofstream(dir / "spec.json") << spec;
  const std::string cmd = std::string(FLUME_EXE) + " study tradeoff " + (dir / "spec.json").string() +
                          " --db " + (dir / "s.sqlite").string() + " --out " + (dir / "out").string() +
                          " > " + (dir / "log.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir / "log.txt");
  const std::string md = slurp(dir / "out" / "tradeoff.md");
  EXPECT_NE(md.find("| coarse | solver.dx=0.05 | ok |"), std::string::npos) << md;
  EXPECT_NE(md.find("fine (reference)"), std::string::npos) << md;
  EXPECT_NE(md.find("| 3D half |"), std::string::npos) << md;
  const std::string csv = slurp(dir / "out" / "tradeoff.csv");
  EXPECT_NE(csv.find("WG1.rms_m"), std::string::npos);
  EXPECT_EQ(csv.find("nan"), std::string::npos) << csv;
  const std::string svg = slurp(dir / "out" / "tradeoff.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("Pareto front"), std::string::npos);
  EXPECT_EQ(plot::test::check_xml(svg).error, "") << "tradeoff.svg is not well-formed XML";
  // Again: nothing reruns (the store has every run), and the same table comes out.
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir / "log.txt");
  EXPECT_NE(slurp(dir / "log.txt").find("4 finished, 0 to run"), std::string::npos) << slurp(dir / "log.txt");
  EXPECT_EQ(slurp(dir / "out" / "tradeoff.md"), md);
  // The runs are a campaign: one row per setting in its store.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "s.sqlite").string().c_str(), &db), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db, "SELECT count(*) FROM runs WHERE status = 'ok'", -1, &st, nullptr);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(st, 0), 4);
  sqlite3_finalize(st);
  // The errors are stored beside the cost: every ok run has error.peak (0 for the reference) and no NaN.
  sqlite3_prepare_v2(db, "SELECT count(*), sum(value IS NULL) FROM metrics WHERE name = 'error.peak'", -1,
                     &st, nullptr);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(st, 0), 4);
  EXPECT_EQ(sqlite3_column_int(st, 1), 0);
  sqlite3_finalize(st);
  sqlite3_close(db);
  // A measured record as the reference: the fine run's gauges as a CSV, and the coarse setting against it
  // gives the errors it had against the fine setting.
  const std::string target = std::string(FLUME_EXE) + " calibrate target " +
                             (dir / "s.sqlite.runs" / "mini" / "run-000000" / "result.h5").string() +
                             " --out " + (dir / "fine.csv").string() + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(target.c_str()), 0);
  std::ofstream(dir / "records.json") << R"({"name": "mini-records", "scene": ")" + kSrc +
                                             R"(/scenes/waseda/waseda_2d.json",
    "overrides": {"solver.end_time": 0.3, "reservoir.forcing.t99_s": 0.1},
    "settings": [{"label": "coarse", "solver.dx": 0.05}, {"label": "coarse cfl 0.8", "solver.dx": 0.05, "solver.cfl": 0.8}],
    "reference": {"records": "fine.csv"}, "outputs": {"gauges": ["WG1", "WG2"], "window_s": [0, 0.3]},
    "run": {"threads": 1}})";
  const std::string rec = std::string(FLUME_EXE) + " study tradeoff " + (dir / "records.json").string() +
                          " --db " + (dir / "s.sqlite").string() + " --out " +
                          (dir / "out-records").string() + " > " + (dir / "log.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(rec.c_str()), 0) << slurp(dir / "log.txt");
  auto row_of = [](const std::string& csv, const std::string& label) {
    const auto at = csv.find("\n\"" + label + "\",");
    return at == std::string::npos ? std::string() : csv.substr(at + 1, csv.find('\n', at + 1) - at - 1);
  };
  const std::string csv_rec = slurp(dir / "out-records" / "tradeoff.csv");
  // Same columns after the label and changes; the error columns agree (the CSV keeps 10 digits of both).
  auto errors = [](const std::string& row) {
    std::vector<std::string> cells;
    std::stringstream ss(row);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    return cells.size() > 11 ? cells[10] + "," + cells[11] : std::string("?");  // error_peak, error_arrival_s
  };
  EXPECT_EQ(errors(row_of(csv_rec, "coarse")), errors(row_of(csv, "coarse"))) << csv_rec << "\n" << csv;
  EXPECT_NE(slurp(dir / "out-records" / "tradeoff.md").find("measured record"), std::string::npos);

  // A bad spec: exit 2 and the field named.
  std::ofstream(dir / "bad.json") << R"({"name": "bad", "scene": ")" + kSrc +
                                         R"(/scenes/waseda/waseda_2d.json",
    "settings": [{"label": "a", "solver.dx": 0.04}, {"label": "b", "solver.ppc": 5}], "reference": {"setting": "a"}})";
  const std::string bad = std::string(FLUME_EXE) + " study tradeoff " + (dir / "bad.json").string() +
                          " --db " + (dir / "b.sqlite").string() + " 2> " + (dir / "err.txt").string();
  const int rc = std::system(bad.c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  EXPECT_NE(slurp(dir / "err.txt").find("settings.1.solver.ppc"), std::string::npos)
      << slurp(dir / "err.txt");
}

}  // namespace
}  // namespace flume::study
