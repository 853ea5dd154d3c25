// Adaptive designs, the two-level Monte Carlo estimator and the calibration posterior against analytic
// answers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "common/errors.h"
#include "linear_gaussian.h"
#include "report/report.h"
#include "surrogate/adaptive.h"
#include "surrogate/multilevel.h"
#include "surrogate/posterior.h"
#include "surrogate/stored.h"
#include "tests/common/run_command.h"
#include "tests/surrogate/test_dir.h"
#include "tests/report/campaign_fixture.h"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace flume::surrogate;

fs::path test_dir() { return flume::test::surrogate_test_dir(); }

flume::sampling::Distribution uniform(double lo, double hi) {
  flume::sampling::Distribution d;
  d.lower = lo;
  d.upper = hi;
  return d;
}

// Conditioning a Gaussian process on one more point never raises its variance anywhere, so within a batch
// (kriging believer, covariance kept) the variance at each pick is at most that of the pick before.
TEST(Adaptive, BatchPicksWhereTheVarianceIsLargestAndItFalls) {
  TrainingData t;
  t.inputs = {"a", "b"};
  t.distributions = {uniform(0, 1), uniform(0, 1)};
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 8; ++i) {
    const double a = u(rng), b = u(rng);
    t.x.push_back({a, b});
    t.y.push_back(std::sin(6 * a) + b * b);
    t.run_ids.push_back(i + 1);
  }
  AdaptiveSettings s;
  s.batch = 6;
  s.candidates = 500;
  const Proposal p = propose_batch(t, s);
  ASSERT_EQ(p.points.size(), 6u);
  for (std::size_t i = 0; i < p.points.size(); ++i) {
    EXPECT_GE(p.points[i][0], 0.0);
    EXPECT_LE(p.points[i][0], 1.0);
    if (i > 0) {
      EXPECT_LE(p.score[i], p.score[i - 1] * (1 + 1e-6)) << "pick " << i;
    }
  }
  EXPECT_GT(p.score.front(), 0.0);
  // Deterministic: the same data and settings propose the same batch.
  EXPECT_EQ(propose_batch(t, s).points, p.points);
  // The exceedance criterion picks near the contour mu = t: U = |mu - t| / sigma small.
  s.criterion = Criterion::kExceedance;
  s.threshold = 0.5;
  s.batch = 3;
  const Proposal q = propose_batch(t, s);
  ASSERT_EQ(q.points.size(), 3u);
  EXPECT_LT(q.score.front(), 2.0);  // a point whose side of t is uncertain (|mu - t| < 2 sigma)
}

// End to end on `flume model ishigami` with x3 fixed (y = sin x1 + 7 sin^2 x2): from 20 runs, batches of 10
// until the kriging's 5-fold Q2 reaches 0.99; a second invocation finds the target met and runs nothing.
TEST(Adaptive, CampaignGrowsToTheTargetQ2AndResumes) {
  const fs::path dir = test_dir();
  {
    std::ofstream(dir / "spec.json") << R"({"name": "adapt", "model": "ishigami", "overrides": {"x3": 0},
      "parameters": [
        {"path": "x1", "distribution": {"type": "uniform", "lower": -3.141592653589793, "upper": 3.141592653589793}},
        {"path": "x2", "distribution": {"type": "uniform", "lower": -3.141592653589793, "upper": 3.141592653589793}}],
      "design": {"type": "lhs", "samples": 20}, "seed": 2})";
  }
  const std::vector<std::string> cmd = {FLUME_EXE, "surrogate", "adapt", (dir / "spec.json").string(), "--db",
                                        (dir / "s.db").string(), "--metric", "y", "--batch", "10", "--max-runs",
                                        "80", "--target-q2", "0.99", "--workers", "2"};
  auto r = flume::test::run_command(cmd, dir, 110);
  ASSERT_EQ(r.rc, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("target reached"), std::string::npos) << r.out;
  const auto rec = stored_surrogate((dir / "s.db").string(), "adapt", "y", Kind::kKriging);
  const json q = json::parse(rec.quality_json);
  EXPECT_GE(q["q2_cv"].get<double>(), 0.99);
  const std::size_t n = q["n_train"].get<std::size_t>();
  EXPECT_LE(n, 80u);
  EXPECT_GT(n, 20u);
  EXPECT_EQ((n - 20) % 10, 0u);
  r = flume::test::run_command(cmd, dir, 110);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("target reached after 0 batch(es), " + std::to_string(n) + " design points"),
            std::string::npos)
      << r.out;
}

// P(sin x1 + 7 sin^2 x2 > t), x1, x2 ~ U(-pi, pi): over x1, P(sin x1 > c) = (pi - 2 asin c) / (2 pi) for c in
// [-1, 1]; the remaining integral over x2 by the midpoint rule on 200,000 points (error far below 1e-4).
double exact_exceedance(double t) {
  const int n = 200000;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double x2 = -M_PI + (i + 0.5) * 2 * M_PI / n, c = t - 7 * std::sin(x2) * std::sin(x2);
    sum += c <= -1 ? 1.0 : c >= 1 ? 0.0 : (M_PI - 2 * std::asin(c)) / (2 * M_PI);
  }
  return sum / n;
}

// A campaign of the Ishigami function over x1 and x2 (x3 = 0: y = sin x1 + 7 sin^2 x2), an LHS of `samples`.
void write_ishigami_x1x2_spec(const fs::path& file, const std::string& name, int samples) {
  std::ofstream(file) << R"({"name": ")" << name << R"(", "model": "ishigami", "overrides": {"x3": 0},
      "parameters": [
        {"path": "x1", "distribution": {"type": "uniform", "lower": -3.141592653589793, "upper": 3.141592653589793}},
        {"path": "x2", "distribution": {"type": "uniform", "lower": -3.141592653589793, "upper": 3.141592653589793}}],
      "design": {"type": "lhs", "samples": )" << samples << R"(}, "seed": 3})";
}

// A threshold in the tail, beyond every run of the first design: the kriging's realisations all stay below it
// and the interval reads zero wide, which is no evidence. `adapt` goes on adding runs until one lies above the
// threshold or the budget is spent (the demo's first threshold, outside its runs, stopped it after the design).
TEST(Adaptive, WidthTargetWaitsForRunsOnBothSidesOfTheThreshold) {
  const fs::path dir = test_dir();
  write_ishigami_x1x2_spec(dir / "spec.json", "adapt-tail", 4);
  const std::string db = (dir / "s.db").string();
  const double t = 7.5;  // y = sin x1 + 7 sin^2 x2 <= 8: P(y > 7.5) is about 0.06
  auto r = flume::test::run_command({FLUME_EXE, "surrogate", "adapt", (dir / "spec.json").string(), "--db", db,
                                     "--metric", "y", "--threshold", "7.5", "--target-width", "0.5", "--batch", "2",
                                     "--max-runs", "30", "--folds", "0", "--workers", "2"},
                                    dir, 110);
  ASSERT_EQ(r.rc, 0) << r.err << r.out;
  const TrainingData data = load_training_data(db, "adapt-tail", "y");
  ASSERT_GE(data.y.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) ASSERT_LE(data.y[i], t) << "the design must lie below t for this test";
  EXPECT_GT(data.y.size(), 4u) << r.out;
  std::size_t above = 0;
  for (const double y : data.y) above += y > t;
  EXPECT_TRUE(above > 0 || data.y.size() == 30u) << "stopped with every run below t: " << r.out;
  EXPECT_NE(r.out.find("not yet evidence"), std::string::npos) << r.out;
}

// The demo's path end to end (scripts/demo): `adapt` by the exceedance criterion (AK-MCS U) at t = 5, then
// `fit --thresholds`, then the report. The added runs gather near the contour y = t; the exact probability
// lies in the kriging's interval, widened by 3 binomial standard deviations of the one sample of input points
// its realisations are drawn on (that sample's own error is not in their spread); the report's distribution
// statistics rest on the LHS runs only and its surrogate section tabulates P with the interval's source.
TEST(Adaptive, ExceedanceCampaignGathersRunsNearTheThresholdAndTheReportShowsP) {
  const fs::path dir = test_dir();
  write_ishigami_x1x2_spec(dir / "spec.json", "adapt-t", 15);
  const std::string db = (dir / "s.db").string();
  auto r = flume::test::run_command({FLUME_EXE, "surrogate", "adapt", (dir / "spec.json").string(), "--db", db,
                                     "--metric", "y", "--threshold", "5", "--target-width", "0.02", "--batch", "5",
                                     "--max-runs", "40", "--folds", "0", "--workers", "2"},
                                    dir, 110);
  ASSERT_EQ(r.rc, 0) << r.err << r.out;
  r = flume::test::run_command({FLUME_EXE, "surrogate", "fit", "--db", db, "--campaign", "adapt-t", "--metric", "y",
                                "--kind", "kriging", "--folds", "0", "--thresholds", "5"},
                               dir, 110);
  ASSERT_EQ(r.rc, 0) << r.err << r.out;
  const TrainingData data = load_training_data(db, "adapt-t", "y");
  ASSERT_GT(data.y.size(), 15u);
  ASSERT_LE(data.y.size(), 40u);
  r = flume::test::run_command({FLUME_EXE, "campaign", "status", "--db", db}, dir, 60);
  EXPECT_NE(r.out.find("'adapt-t': " + std::to_string(data.y.size()) + " runs"), std::string::npos) << r.out;
  double initial = 0, added = 0;
  for (std::size_t i = 0; i < data.y.size(); ++i) (i < 15 ? initial : added) += std::abs(data.y[i] - 5);
  initial /= 15;
  added /= static_cast<double>(data.y.size() - 15);
  EXPECT_LT(added, 0.5 * initial) << "mean |y - t|: LHS " << initial << ", added " << added;

  const json q = json::parse(stored_surrogate(db, "adapt-t", "y", Kind::kKriging).quality_json);
  const json& c = q["exceedance"];
  ASSERT_EQ(c["thresholds"].size(), 1u);
  const double exact = exact_exceedance(5), lo = c["lo"][0].get<double>(), hi = c["hi"][0].get<double>();
  const std::size_t m = c["band_points"].get<std::size_t>();
  ASSERT_GT(m, 0u);
  const double slack = 3 * std::sqrt(exact * (1 - exact) / static_cast<double>(m));
  std::printf("%zu runs, Q2 LOO %.4f, P(y > 5) %.4f [%.4f, %.4f] on %zu points, exact %.4f; mean |y - 5| LHS %.3f, "
              "added %.3f\n",
              data.y.size(), q["q2_cv"].get<double>(), c["p"][0].get<double>(), lo, hi, m, exact, initial, added);
  EXPECT_GE(exact, lo - slack) << "P " << c["p"][0] << " [" << lo << ", " << hi << "]";
  EXPECT_LE(exact, hi + slack) << "P " << c["p"][0] << " [" << lo << ", " << hi << "]";

  flume::report::ReportOptions o;
  o.db_file = db;
  o.campaign = "adapt-t";
  o.out_dir = (dir / "out").string();
  o.stats.bootstrap = 100;
  const auto rep = flume::report::build_report(o);
  EXPECT_EQ(rep.sample.size(), 15u);
  EXPECT_NE(rep.sample_note.find("added by 'flume surrogate adapt'"), std::string::npos) << rep.sample_note;
  flume::report::write_report(rep);
  const std::string html = flume::test::read_file(dir / "out" / "report.html");
  const auto at = html.find("<section id=surrogates>");
  ASSERT_NE(at, std::string::npos);
  const std::string section = html.substr(at, html.find("</section>", at) - at);
  EXPECT_NE(section.find("<th>t = 5</th>"), std::string::npos);
  EXPECT_NE(section.find("conditional realisations of the kriging process on one sample of " + std::to_string(m)),
            std::string::npos);
}

// Forrester, Sobester & Keane (2007) two-fidelity function, x ~ U(0, 1):
//   f_H = (6x - 2)^2 sin(12x - 4),  f_L = 0.5 f_H + 10 (x - 0.5) - 5
// E[f_H] = (1/6) [F(u)] from -2 to 4 with F(u) = -u^2 cos(2u)/2 + u sin(2u)/2 + cos(2u)/4 (u = 6x - 2).
double f_high(double x) { return std::pow(6 * x - 2, 2) * std::sin(12 * x - 4); }
double f_low(double x) { return 0.5 * f_high(x) + 10 * (x - 0.5) - 5; }
double exact_mean_high() {
  auto F = [](double u) { return -u * u * std::cos(2 * u) / 2 + u * std::sin(2 * u) / 2 + std::cos(2 * u) / 4; };
  return (F(4) - F(-2)) / 6;
}

// The estimator's variance formula against the spread of the estimate over independent repetitions: 300
// repetitions estimate a variance to +-8 % (one standard deviation, sqrt(2 / 299)); 30 % is 3.7 of them.
TEST(Multilevel, VarianceFormulaMatchesRepetitionsAndTheMeanIsUnbiased) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> estimates;
  double predicted = 0;
  for (int rep = 0; rep < 300; ++rep) {
    TwoLevelSamples s;
    s.cost_low_s = 1;
    s.cost_high_s = 10;
    for (int i = 0; i < 200; ++i) s.low_only.push_back(f_low(u(rng)));
    for (int i = 0; i < 20; ++i) {
      const double x = u(rng);
      s.pair_low.push_back(f_low(x));
      s.pair_high.push_back(f_high(x));
    }
    const auto e = two_level_estimate(s);
    estimates.push_back(e.mean);
    predicted += e.variance / 300;
  }
  double mean = 0, var = 0;
  for (double e : estimates) mean += e / estimates.size();
  for (double e : estimates) var += (e - mean) * (e - mean) / (estimates.size() - 1);
  EXPECT_NEAR(var / predicted, 1.0, 0.3);
  EXPECT_NEAR(mean, exact_mean_high(), 4 * std::sqrt(var / estimates.size()));
}

// From the store: a low campaign of 400 Monte Carlo points and a high one whose 40 points are the first 40 of
// the same seeded sequence (so they pair; two parameters, as a design drawn parameter by parameter shares only
// the first one's values); the interval holds the exact mean.
TEST(Multilevel, PairsTwoCampaignsOfAStore) {
  const fs::path dir = test_dir();
  const std::string db = (dir / "s.db").string();
  auto spec = [](const std::string& name, int n) {
    return R"({"name": ")" + name + R"(", "model": "ishigami", "parameters": [{"path": "x1", "distribution":
      {"type": "uniform", "lower": 0, "upper": 1}}, {"path": "x2", "distribution": {"type": "uniform", "lower": 0,
      "upper": 1}}], "design": {"type": "monte_carlo", "samples": )" +
           std::to_string(n) + R"(}, "seed": 7})";
  };
  flume::test::make_campaign(db, spec("low", 400), [](const std::vector<double>& x, std::int64_t) {
    return flume::test::ok_outcome({{"y", f_low(x[0])}});
  });
  flume::test::make_campaign(db, spec("high", 40), [](const std::vector<double>& x, std::int64_t) {
    return flume::test::ok_outcome({{"y", f_high(x[0])}});
  });
  const auto s = load_two_levels(db, "low", "high", "y", 1.0, 10.0);
  ASSERT_EQ(s.pair_low.size(), 40u);
  EXPECT_EQ(s.low_only.size(), 360u);
  const auto e = two_level_estimate(s, 0.999);
  std::printf("Forrester two-level: %.4f [%.4f, %.4f] exact %.4f; cost %.0f; high alone for the same variance %.0f\n",
              e.mean, e.lo, e.hi, exact_mean_high(), e.cost_s, e.high_only_cost_s);
  EXPECT_LE(e.lo, exact_mean_high());
  EXPECT_GE(e.hi, exact_mean_high());
  EXPECT_DOUBLE_EQ(e.cost_s, 360 * 1.0 + 40 * 11.0);
  EXPECT_NEAR(e.high_only_cost_s, e.v_high * 10.0 / e.variance, 1e-9 * e.high_only_cost_s);
  // At the optimal allocation the variance for a cost C is (sqrt(V0 c_L) + sqrt(V1 (c_H + c_L)))^2 / C (Giles
  // 2008, eq. (6)): check the printed ratio against the estimator's own variance at that allocation.
  const double n1 = 1000, n0 = e.optimal_n0_per_n1 * n1, cost = n0 * 1.0 + n1 * 11.0;
  const double var_opt = e.v0 / n0 + e.v1 / n1;
  EXPECT_NEAR(e.optimal_cost_ratio, e.v_high * 10.0 / var_opt / cost, 1e-9 * e.optimal_cost_ratio);
  EXPECT_GT(e.correlation, 0.0);
  EXPECT_LE(e.correlation, 1.0);
  EXPECT_THROW(load_two_levels(db, "low", "low_missing", "y"), flume::InputError);
}

// A linear model y = a + b t observed with Gaussian noise: under a flat prior the posterior of (a, b) is
// Gaussian with the least-squares mean and covariance sigma^2 (X^T X)^-1. The misfit's surrogate is fitted on
// evaluations as an optimizer and its profile would leave them: a coarse grid over the bounds and a finer one
// around the optimum.
TEST(Posterior, LinearGaussianModelHasItsAnalyticPosterior) {
  const flume::test::LinearGaussian g = flume::test::linear_gaussian(50, 0.1);
  const int n = g.n;
  const double sigma = g.sigma;
  const std::vector<double>& t = g.t;
  const std::vector<double>& y = g.y;
  const double a_hat = g.mean[0], b_hat = g.mean[1], sd_a = g.sd[0], sd_b = g.sd[1];
  auto ssr = [&](double a, double b) {
    double s = 0;
    for (int i = 0; i < n; ++i) s += std::pow(y[i] - a - b * t[i], 2);
    return s;
  };
  MisfitData d;
  d.names = {"a", "b"};
  d.lower = {0, 1};
  d.upper = {2, 3};
  d.n_residuals = n;
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j <= 4; ++j) {
      d.points.push_back({0.5 * i, 1 + 0.5 * j});
      d.ssr.push_back(ssr(d.points.back()[0], d.points.back()[1]));
    }
  for (int i = -3; i <= 3; ++i)
    for (int j = -3; j <= 3; ++j) {
      d.points.push_back({a_hat + 1.5 * i * sd_a, b_hat + 1.5 * j * sd_b});
      d.ssr.push_back(ssr(d.points.back()[0], d.points.back()[1]));
    }
  PosteriorSettings s;
  s.noise_m = sigma;
  s.draws = 200;
  const Posterior p = misfit_posterior(d, s);
  ASSERT_EQ(p.parameters.size(), 2u);
  ASSERT_EQ(p.draws.size(), 200u);
  const double sd[2] = {sd_a, sd_b}, mean[2] = {a_hat, b_hat};
  for (int j = 0; j < 2; ++j) {
    const auto& q = p.parameters[j];
    std::printf("%s: posterior mean %.4f, 95 %% [%.4f, %.4f]; analytic %.4f +- %.4f; acceptance %.2f, misfit Q2 %.4f\n",
                q.name.c_str(), q.mean, q.lo, q.hi, mean[j], 1.959964 * sd[j], p.acceptance, p.q2);
    // MCMC error: 20000 correlated samples are worth a few hundred independent ones (0.1 sd).
    EXPECT_NEAR(q.mean, mean[j], 0.25 * sd[j]) << q.name;
    EXPECT_NEAR((q.hi - q.lo) / (2 * 1.959964 * sd[j]), 1.0, 0.15) << q.name;
    // The draws for the predictive runs are the posterior's too: 200 of them, 100 chain steps apart, give
    // its mean to 0.25 sd and its sd to 20 % (a standard error of 5 % if independent, more along a chain).
    double m = 0, v = 0;
    for (const auto& x : p.draws) m += x[j] / p.draws.size();
    for (const auto& x : p.draws) v += (x[j] - m) * (x[j] - m) / (p.draws.size() - 1);
    EXPECT_NEAR(m, mean[j], 0.25 * sd[j]) << q.name;
    EXPECT_NEAR(std::sqrt(v) / sd[j], 1.0, 0.2) << q.name;
  }
  // Half the noise, half the width.
  s.noise_m = sigma / 2;
  const Posterior half = misfit_posterior(d, s);
  for (int j = 0; j < 2; ++j)
    EXPECT_NEAR((half.parameters[j].hi - half.parameters[j].lo) / (p.parameters[j].hi - p.parameters[j].lo), 0.5,
                0.1);
}

// The predictive runs' spec is a campaign spec `flume campaign run` accepts: one list point per draw on the
// calibration's scene and overrides, the simulated time replaced, a time shift of the comparison left out.
TEST(Posterior, PredictiveSpecIsACampaignOfTheDraws) {
  const fs::path dir = flume::test::surrogate_test_dir();
  { std::ofstream(dir / "scene.json") << "{}"; }
  MisfitData d;
  d.names = {"reservoir.forcing.t99_s", "objective.time_shift_s"};
  d.spec_json = nlohmann::json{{"scene", (dir / "scene.json").string()},
                               {"overrides", {{"solver.dx", 0.02}, {"solver.end_time", 2.2}}}}
                    .dump();
  Posterior post;
  post.parameters = {{"reservoir.forcing.t99_s", 0.82}, {"objective.time_shift_s", 0.0}};
  post.draws = {{0.8, 0.01}, {0.9, -0.02}, {0.85, 0.0}};
  const auto spec = nlohmann::json::parse(predictive_spec(d, post, "exp", 6.0));
  EXPECT_EQ(spec["name"], "exp-predictive");
  EXPECT_EQ(spec["overrides"]["solver.end_time"].get<double>(), 6.0);
  EXPECT_EQ(spec["overrides"]["solver.dx"].get<double>(), 0.02);
  ASSERT_EQ(spec["design"]["points"].size(), 4u);
  EXPECT_EQ(spec["design"]["points"][0]["label"], "optimum");
  EXPECT_EQ(spec["design"]["points"][0]["reservoir.forcing.t99_s"].get<double>(), 0.82);
  EXPECT_EQ(spec["design"]["points"][2]["label"], "draw-002");
  EXPECT_EQ(spec["design"]["points"][2]["reservoir.forcing.t99_s"].get<double>(), 0.9);
  EXPECT_FALSE(spec["design"]["points"][2].contains("objective.time_shift_s"));
  EXPECT_FALSE(spec["design"]["points"][0].contains("objective.time_shift_s"));
  fs::remove(dir / "scene.json");
  EXPECT_THROW(predictive_spec(d, post, "exp", 6.0), flume::InputError) << "the scene is gone";
  d.spec_json = R"({"model": "gauge"})";
  EXPECT_THROW(predictive_spec(d, post, "exp", 6.0), flume::InputError) << "a stand-in model";
}

}  // namespace
