// Metrics that exist in part of the input box only (a gauge's arrival where the bore reaches it, and its
// peak given that it does): the fit on the runs inside and the classifier of where inside is, on an analytic
// stand-in whose edge and values are known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "tests/report/campaign_fixture.h"
#include "tests/surrogate/test_dir.h"
#include "common/errors.h"
#include "surrogate/stored.h"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace flume::surrogate;

// A bore of height h = x1 + x2 / 2 (x1, x2 ~ U(0, 1)) overtops a quay of crest 0.6: it reaches the gauge
// iff h > 0.6, which holds on a share 1 - integral_0^1 (0.6 - x2 / 2) dx2 = 0.65 of the box. There it
// arrives at 1 / (h - 0.3) and peaks at the dry level plus the excess; elsewhere the peak is the dry level
// (a kink at the edge) and there is no arrival.
constexpr double kCrest = 0.6, kDry = 0.025, kShareInside = 0.65;

flume::store::RunOutcome overtopping(const std::vector<double>& x) {
  const double h = x[0] + 0.5 * x[1];
  if (h <= kCrest) return flume::test::ok_outcome({{"peak", kDry}});
  return flume::test::ok_outcome({{"peak", kDry + (h - kCrest)}, {"arrival", 1.0 / (h - 0.3)}});
}

void make_runs(const fs::path& db, const std::string& name, const std::string& design, int runs, int seed) {
  const std::string x = R"({"path": "x1", "distribution": {"type": "uniform", "lower": 0, "upper": 1}},
                           {"path": "x2", "distribution": {"type": "uniform", "lower": 0, "upper": 1}})";
  flume::test::make_campaign(db.string(),
                             R"({"name": ")" + name + R"(", "model": "ishigami", "parameters": [)" + x +
                                 R"(], "design": {"type": ")" + design + R"(", "samples": )" +
                                 std::to_string(runs) + R"(}, "seed": )" + std::to_string(seed) + "}",
                             [](const std::vector<double>& x, std::int64_t) { return overtopping(x); });
}

// The arrival is fitted where it exists and validated there; the classifier places the edge. 40 runs in two
// inputs are h = 1/sqrt(40) = 0.16 apart, so a classifier built from them knows the edge (1.12 long) to about
// half a spacing: only the runs within h/2 of it, 0.18 of the box (7 of 40), can be misjudged, hence an
// accuracy of at least 0.8; the share inside is asked to 0.05, an edge misplaced by 0.3 h on average.
TEST(SurrogateCondition, ArrivalFittedWhereItExistsWithAClassifierOfWhere) {
  const fs::path dir = flume::test::surrogate_test_dir();
  make_runs(dir / "c.db", "fit", "lhs", 40, 3);
  make_runs(dir / "c.db", "check", "monte_carlo", 30, 9);
  FitSettings s;
  s.kind = Kind::kKriging;
  s.folds = 0;
  s.validation = "check";
  s.bootstrap = 0;
  const json q = json::parse(fit_and_store((dir / "c.db").string(), "fit", "arrival", s).record.quality_json);
  ASSERT_TRUE(q.contains("classifier"));
  const json& c = q["classifier"];
  std::printf("arrival: Q2 LOO %.4f, held back %.4f on %zu runs; classifier %zu in / %zu out, accuracy LOO %.3f, "
              "held back %.3f, P(inside) %.4f (exact %.2f)\n",
              q["q2_cv"].get<double>(), q["q2_holdout"].get<double>(), q["n_holdout"].get<std::size_t>(),
              c["inside"].get<std::size_t>(), c["outside"].get<std::size_t>(), c["accuracy_cv"].get<double>(),
              c["accuracy_holdout"].get<double>(), c["p_inside"].get<double>(), kShareInside);
  EXPECT_EQ(c["inside"].get<std::size_t>(), q["n_train"].get<std::size_t>());
  EXPECT_EQ(c["inside"].get<std::size_t>() + c["outside"].get<std::size_t>(), 40u);
  EXPECT_EQ(c["holdout_inside"].get<std::size_t>(), q["n_holdout"].get<std::size_t>());
  EXPECT_GE(q["q2_cv"].get<double>(), 0.95);
  EXPECT_GE(q["q2_holdout"].get<double>(), 0.95);
  EXPECT_GE(c["accuracy_cv"].get<double>(), 0.8);
  EXPECT_GE(c["accuracy_holdout"].get<double>(), 0.8);
  EXPECT_NEAR(c["p_inside"].get<double>(), kShareInside, 0.05);
}

// The peak exists everywhere but has a kink at the edge: given the arrival, it is the smooth part and the
// kriging is near exact; fitted over the whole box the kink costs it.
TEST(SurrogateCondition, PeakGivenArrivalIsTheSmoothPart) {
  const fs::path dir = flume::test::surrogate_test_dir();
  make_runs(dir / "c.db", "fit", "lhs", 40, 3);
  FitSettings s;
  s.kind = Kind::kKriging;
  s.folds = 0;
  s.bootstrap = 0;
  const double q2_whole =
      json::parse(fit_and_store((dir / "c.db").string(), "fit", "peak", s).record.quality_json)["q2_cv"].get<double>();
  s.given = "arrival";
  const auto given = fit_and_store((dir / "c.db").string(), "fit", "peak", s);
  ASSERT_TRUE(given.refitted) << "the condition is part of what decides a fit";
  const json q = json::parse(given.record.quality_json);
  EXPECT_EQ(q["given"].get<std::string>(), "arrival");
  std::printf("peak: Q2 LOO over the box %.4f, given the arrival %.4f\n", q2_whole, q["q2_cv"].get<double>());
  EXPECT_GE(q["q2_cv"].get<double>(), 0.99) << "a linear function of the inputs where the bore arrives";
  EXPECT_LT(q2_whole, q["q2_cv"].get<double>());
  EXPECT_TRUE(q.contains("classifier"));
  EXPECT_THROW(
      {
        s.given = "no_such_metric";
        fit_and_store((dir / "c.db").string(), "fit", "peak", s);
      },
      flume::InputError);
}

}  // namespace
