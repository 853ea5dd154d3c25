// Surrogates against analytic answers: the Ishigami function's Sobol' indices (closed form, Ishigami & Homma
// 1990) and a chi-square exceedance probability, from campaigns of at most 200 runs built in-process
// (tests/report/campaign_fixture.h); the store's surrogate table; `flume surrogate` on the command line.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "tests/common/run_command.h"
#include "tests/surrogate/test_dir.h"
#include "tests/report/campaign_fixture.h"
#include "common/errors.h"
#include "report/report.h"
#include "surrogate/stored.h"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace flume::surrogate;

fs::path test_dir() { return flume::test::surrogate_test_dir(); }

const double kA = 7.0, kB = 0.1;

double ishigami(const std::vector<double>& x) {
  return std::sin(x[0]) + kA * std::pow(std::sin(x[1]), 2) + kB * std::pow(x[2], 4) * std::sin(x[0]);
}

std::string ishigami_spec(int runs, const std::string& name = "ishigami", int seed = 5) {
  std::string x;
  for (const char* v : {"x1", "x2", "x3"})
    x += std::string(x.empty() ? "" : ", ") + R"({"path": ")" + v +
         R"(", "distribution": {"type": "uniform", "lower": -3.141592653589793, "upper": 3.141592653589793}})";
  return R"({"name": ")" + name + R"(", "model": "ishigami", "parameters": [)" + x +
         R"(], "design": {"type": "lhs", "samples": )" + std::to_string(runs) + R"(}, "seed": )" +
         std::to_string(seed) + "}";
}

void make_ishigami(const fs::path& db, int runs, const std::string& name = "ishigami", int seed = 5) {
  flume::test::make_campaign(db.string(), ishigami_spec(runs, name, seed), [](const std::vector<double>& x, std::int64_t) {
    return flume::test::ok_outcome({{"y", ishigami(x)}});
  });
}

// 200 runs: the issue's budget for the Sobol' indices and Q2.
TEST(Chaos, IshigamiSobolIndicesAndQ2From200Runs) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 200);
  FitSettings s;
  const auto fit = fit_and_store((dir / "s.db").string(), "ishigami", "y", s);
  ASSERT_TRUE(fit.refitted);
  const json q = json::parse(fit.record.quality_json);
  EXPECT_GE(q["q2_cv"].get<double>(), 0.99) << "5-fold Q2";

  // Exact indices (Sobol' & Levitan 1999; Saltelli et al. 2008, sec. 4.3): V1, V2, V13 and V.
  const double pi4 = std::pow(M_PI, 4), pi8 = std::pow(M_PI, 8);
  const double v1 = 0.5 * std::pow(1 + kB * pi4 / 5, 2), v2 = kA * kA / 8, v13 = 8 * kB * kB * pi8 / 225;
  const double v = v1 + v2 + v13;
  const double first[3] = {v1 / v, v2 / v, 0.0}, total[3] = {(v1 + v13) / v, v2 / v, v13 / v};
  std::printf("Ishigami, 200 runs: Q2 %zu-fold %.5f, degree %d, %d terms\n", q["folds"].get<std::size_t>(),
              q["q2_cv"].get<double>(), q["degree"].get<int>(), q["terms"].get<int>());
  for (int j = 0; j < 3; ++j) {
    const json& f = q["sobol"]["first"][j];
    const json& t = q["sobol"]["total"][j];
    std::printf("x%d: S %.4f [%.4f, %.4f] exact %.4f, ST %.4f [%.4f, %.4f] exact %.4f\n", j + 1,
                f["value"].get<double>(), f["lo"].get<double>(), f["hi"].get<double>(), first[j],
                t["value"].get<double>(), t["lo"].get<double>(), t["hi"].get<double>(), total[j]);
    EXPECT_NEAR(f["value"].get<double>(), first[j], 0.02) << "first-order index of x" << j + 1;
    EXPECT_NEAR(t["value"].get<double>(), total[j], 0.02) << "total index of x" << j + 1;
    // The bootstrap interval brackets its own estimate.
    EXPECT_LE(f["lo"].get<double>(), f["value"].get<double>() + 1e-12);
    EXPECT_GE(f["hi"].get<double>(), f["value"].get<double>() - 1e-12);
    EXPECT_LE(t["lo"].get<double>(), t["value"].get<double>() + 1e-12);
    EXPECT_GE(t["hi"].get<double>(), t["value"].get<double>() - 1e-12);
  }
  EXPECT_GT(q["sobol"]["replicates"].get<int>(), 150);
  // The mean and variance of the expansion are the function's: E[Y] = a / 2.
  EXPECT_NEAR(q["mean"].get<double>(), kA / 2, 0.02 * std::sqrt(v));
  EXPECT_NEAR(q["std"].get<double>() * q["std"].get<double>(), v, 0.02 * v);
}

// The stored model is the fitted one: predictions at new points match the function (Q2 >= 0.99 means an
// RMS error of at most 10 % of the output's standard deviation).
TEST(Chaos, StoredModelPredicts) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 200);
  FitSettings s;
  s.bootstrap = 0;
  const auto fit = fit_and_store((dir / "s.db").string(), "ishigami", "y", s);
  const Surrogate model(Kind::kChaos, stored_surrogate((dir / "s.db").string(), "ishigami", "y", Kind::kChaos).model);
  std::vector<std::vector<double>> pts;
  for (int i = 0; i < 50; ++i) pts.push_back({-3 + 0.12 * i, 2.9 - 0.11 * i, -3 + 0.123 * i});
  const auto y = model.predict(pts);
  double sse = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) sse += std::pow(y[i] - ishigami(pts[i]), 2);
  const double std_y = json::parse(fit.record.quality_json)["std"].get<double>();
  EXPECT_LT(std::sqrt(sse / pts.size()), 0.1 * std_y);
}

// Kriging interpolates: at a run the prediction is the run's value and the variance vanishes (up to the
// small nugget OpenTURNS adds for conditioning); held-back runs give an independent Q2.
TEST(Kriging, InterpolatesRunsAndValidatesOnHeldBackRuns) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 120);
  FitSettings s;
  s.kind = Kind::kKriging;
  s.holdout = 20;
  s.bootstrap = 50;
  s.mc_size = 4000;
  const auto fit = fit_and_store((dir / "s.db").string(), "ishigami", "y", s);
  const json q = json::parse(fit.record.quality_json);
  EXPECT_EQ(q["n_train"].get<int>(), 100);
  EXPECT_EQ(q["n_holdout"].get<int>(), 20);
  EXPECT_TRUE(q["q2_holdout"].is_number());
  EXPECT_TRUE(q["q2_cv"].is_number());
  const auto data = load_training_data((dir / "s.db").string(), "ishigami", "y");
  const Surrogate model(Kind::kKriging, fit.record.model);
  const std::vector<std::vector<double>> at(data.x.begin(), data.x.begin() + 5);
  const auto y = model.predict(at), var = model.variance(at);
  const double std_y = q["std"].get<double>();
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(y[i], data.y[i], 1e-3 * std_y);
    EXPECT_LT(var[i], 1e-4 * std_y * std_y);
  }
}

// Y = X1^2 + X2^2 + X3^2 with standard normal inputs is chi-square with 3 degrees of freedom:
// P(Y > t) = 2 (1 - Phi(sqrt t)) + sqrt(2 t / pi) exp(-t / 2). A degree-2 Hermite expansion is exact, so the
// surrogate's curve differs from it by Monte Carlo error only: within 4 binomial standard deviations of its
// sample, and inside its band.
TEST(Chaos, ExceedanceProbabilityOfAKnownModel) {
  const fs::path dir = test_dir();
  std::string x;
  for (const char* v : {"x1", "x2", "x3"})
    x += std::string(x.empty() ? "" : ", ") + R"({"path": ")" + v +
         R"(", "distribution": {"type": "normal", "mean": 0, "std": 1}})";
  flume::test::make_campaign(
      (dir / "s.db").string(),
      R"({"name": "chi2", "model": "ishigami", "parameters": [)" + x +
          R"(], "design": {"type": "lhs", "samples": 60}, "seed": 3})",
      [](const std::vector<double>& v, std::int64_t) {
        return flume::test::ok_outcome({{"r2", v[0] * v[0] + v[1] * v[1] + v[2] * v[2]}});
      });
  FitSettings s;
  s.thresholds = {1.0, 3.0, 7.814727903};  // the last one is the 95 % quantile: P = 0.05
  const auto fit = fit_and_store((dir / "s.db").string(), "chi2", "r2", s);
  const json q = json::parse(fit.record.quality_json);
  EXPECT_GE(q["q2_cv"].get<double>(), 0.999);
  const auto& c = q["exceedance"];
  for (std::size_t i = 0; i < s.thresholds.size(); ++i) {
    const double t = s.thresholds[i];
    const double exact = std::erfc(std::sqrt(t / 2)) + std::sqrt(2 * t / M_PI) * std::exp(-t / 2);
    const double p = c["p"][i].get<double>();
    const double sd = std::sqrt(exact * (1 - exact) / q["exceedance"]["mc_size"].get<double>());
    std::printf("chi2(3): P(Y > %.4f) = %.4f [%.4f, %.4f], exact %.4f\n", t, p, c["lo"][i].get<double>(),
                c["hi"][i].get<double>(), exact);
    EXPECT_NEAR(p, exact, 4 * sd) << "t = " << t;
    EXPECT_LE(c["lo"][i].get<double>(), exact) << "t = " << t;
    EXPECT_GE(c["hi"][i].get<double>(), exact) << "t = " << t;
  }
  EXPECT_NEAR(c["p"][2].get<double>(), 0.05, 0.006);
}

// A fit is redone only when its runs, their values or its settings change.
TEST(Store, FitIsIdempotentAndFollowsTheRuns) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 40);
  FitSettings s;
  s.bootstrap = 20;
  s.mc_size = 2000;
  const std::string db = (dir / "s.db").string();
  EXPECT_TRUE(fit_and_store(db, "ishigami", "y", s).refitted);
  EXPECT_FALSE(fit_and_store(db, "ishigami", "y", s).refitted);
  const auto first = stored_surrogate(db, "ishigami", "y", Kind::kChaos);
  EXPECT_EQ(json::parse(first.runs_json)["train"].size(), 40u);
  {
    flume::store::CampaignStore st(db);
    st.record_metrics(json::parse(first.runs_json)["train"][0].get<std::int64_t>(), {{"y", 123.0}});
  }
  EXPECT_TRUE(fit_and_store(db, "ishigami", "y", s).refitted);
  s.degree = 3;
  EXPECT_TRUE(fit_and_store(db, "ishigami", "y", s).refitted);
  EXPECT_EQ(stored_surrogate_list(db, "ishigami").size(), 1u);  // replaced, not added
}

// Held-back runs from another campaign of the same parameters: the fit uses none of them.
TEST(Store, ValidationCampaignRunsAreHeldBack) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 30);
  make_ishigami(dir / "s.db", 12, "check", 9);
  FitSettings s;
  s.bootstrap = 0;
  s.mc_size = 500;
  s.validation = "check";
  const auto fit = fit_and_store((dir / "s.db").string(), "ishigami", "y", s);
  const json q = json::parse(fit.record.quality_json), runs = json::parse(fit.record.runs_json);
  EXPECT_EQ(q["n_train"].get<int>(), 30);
  EXPECT_EQ(q["n_holdout"].get<int>(), 12);
  EXPECT_TRUE(q["q2_holdout"].is_number());
  for (const auto& id : runs["holdout"]) EXPECT_GT(id.get<int>(), 30);  // the second campaign's runs
  s.holdout = 3;
  EXPECT_THROW(fit_and_store((dir / "s.db").string(), "ishigami", "y", s), flume::InputError);
}

// A store written before surrogates existed (no surrogates table) still opens: read-only it lists none,
// opened for writing it gains the table.
TEST(Store, OlderFilesStayReadable) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 10);
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "s.db").c_str(), &h), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(h, "DROP TABLE surrogates", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(h);
  {
    flume::store::CampaignStore ro((dir / "s.db").string(), true);
    EXPECT_TRUE(ro.surrogates(1).empty());
  }
  FitSettings s;
  s.bootstrap = 0;
  s.mc_size = 500;
  EXPECT_TRUE(fit_and_store((dir / "s.db").string(), "ishigami", "y", s).refitted);
}

// The report shows each stored surrogate: its Q2, the chaos Sobol' indices beside the sampling estimates
// (rank correlations on an LHS design) and the exceedance curve with its band; summary.json has the numbers.
TEST(Report, SurrogateSectionShowsQualitySobolAndExceedance) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 80);
  FitSettings s;
  s.bootstrap = 50;
  s.mc_size = 4000;
  s.holdout = 10;
  fit_and_store((dir / "s.db").string(), "ishigami", "y", s);
  flume::report::ReportOptions o;
  o.db_file = (dir / "s.db").string();
  o.campaign = "ishigami";
  o.out_dir = (dir / "out").string();
  o.stats.bootstrap = 100;
  const auto r = flume::report::build_report(o);
  ASSERT_EQ(r.surrogates.size(), 1u);
  EXPECT_EQ(r.surrogates[0].n_train, 70u);
  EXPECT_EQ(r.surrogates[0].first.size(), 3u);
  flume::report::write_report(r);
  const std::string html = flume::test::read_file(dir / "out" / "report.html");
  const auto at = html.find("<section id=surrogates>");
  ASSERT_NE(at, std::string::npos);
  const std::string section = html.substr(at, html.find("</section>", at) - at);
  EXPECT_NE(section.find("Q2 (10 held back)"), std::string::npos);
  EXPECT_NE(section.find("<th>Spearman</th><th>PRCC</th>"), std::string::npos);
  EXPECT_NE(section.find("<svg"), std::string::npos);
  const json summary = json::parse(flume::test::read_file(dir / "out" / "summary.json"));
  ASSERT_EQ(summary["surrogates"].size(), 1u);
  EXPECT_TRUE(summary["surrogates"][0]["q2_holdout"].is_number());
  EXPECT_EQ(summary["surrogates"][0]["exceedance"].size(), 25u);
  EXPECT_TRUE(summary["surrogates"][0]["sobol"].contains("x2"));
}

flume::test::CommandResult flume_cmd(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> v = {FLUME_EXE};
  v.insert(v.end(), args.begin(), args.end());
  return flume::test::run_command(v, dir, 110);
}

TEST(Cli, FitSobolPredictAndBadInput) {
  const fs::path dir = test_dir();
  make_ishigami(dir / "s.db", 60);
  const std::string db = (dir / "s.db").string();
  auto r = flume_cmd({"surrogate", "fit", "--db", db, "--campaign", "ishigami", "--metric", "y", "--bootstrap", "20"}, dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("y chaos (fitted)"), std::string::npos) << r.out;
  r = flume_cmd({"surrogate", "fit", "--db", db, "--campaign", "ishigami", "--metric", "y", "--bootstrap", "20"}, dir);
  EXPECT_NE(r.out.find("y chaos (up to date)"), std::string::npos) << r.out;
  r = flume_cmd({"surrogate", "sobol", "--db", db, "--campaign", "ishigami", "--metric", "y"}, dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("\nx2,"), std::string::npos) << r.out;
  r = flume_cmd({"surrogate", "predict", "--db", db, "--campaign", "ishigami", "--metric", "y", "--at", "x1=0,x2=0,x3=0"}, dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("x1,x2,x3,y"), std::string::npos) << r.out;

  r = flume_cmd({"surrogate", "fit", "--db", db, "--campaign", "ishigami", "--metric", "nope"}, dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err.rfind(db + ": --metric: campaign 'ishigami' has no metric 'nope' (it has: y)", 0), 0u) << r.err;
  r = flume_cmd({"surrogate", "fit", "--db", db, "--campaign", "ishigami", "--metric", "y", "--holdout", "58"}, dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("--holdout"), std::string::npos) << r.err;
  r = flume_cmd({"surrogate", "sobol", "--db", db, "--campaign", "ishigami", "--metric", "y", "--kind", "x"}, dir);
  EXPECT_EQ(r.rc, 2);
  r = flume_cmd({"surrogate", "posterior", "--db", db, "--calibration", "ishigami", "--noise-m", "0.002"}, dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err.rfind(db + ": --calibration: 'ishigami' is a campaign, not a calibration", 0), 0u) << r.err;
  r = flume_cmd({"surrogate", "posterior", "--db", db, "--calibration", "ishigami", "--noise-m", "0.002",
                 "--surrogate", "misfit"},
                dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err.rfind(db + ": --calibration: 'ishigami' is a campaign, not a calibration", 0), 0u) << r.err;
  r = flume_cmd({"surrogate", "posterior", "--db", db, "--calibration", "ishigami", "--noise-m", "0.002",
                 "--surrogate", "chaos"},
                dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err.rfind("command line: --surrogate: must be series or misfit (got 'chaos')", 0), 0u) << r.err;
  r = flume_cmd({"surrogate", "posterior", "--db", db, "--calibration", "ishigami", "--noise-m", "0.002",
                 "--surrogate", "misfit", "--neighbourhood", "2"},
                dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err.rfind("command line: --neighbourhood: goes with the series emulator", 0), 0u) << r.err;
  r = flume_cmd({"surrogate", "multilevel", "--db", db, "--low", "ishigami", "--metric", "y"}, dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("--high"), std::string::npos) << r.err;
  r = flume_cmd({"surrogate", "fit", "--db", db, "--campaign", "ishigami", "--metric", "y", "--folds", "-1"}, dir);
  EXPECT_EQ(r.rc, 2);
  EXPECT_EQ(r.err.rfind("command line: --folds: must be a number in [0, 100000] (got '-1')", 0), 0u) << r.err;
}

}  // namespace
