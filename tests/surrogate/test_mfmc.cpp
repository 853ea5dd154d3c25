// Multi-fidelity Monte Carlo (Peherstorfer, Willcox & Gunzburger 2016) against analytic levels: the variance
// formula against the spread of repeated estimates, the optimal weight as the regression coefficient, the
// optimal allocation as the minimum of the variance for a budget, the ordering conditions, the two-level
// unit-weight case against the Giles estimator, the store and the command line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <numbers>
#include <random>

#include "surrogate/mfmc.h"
#include "surrogate/multilevel.h"
#include "tests/common/run_command.h"
#include "tests/report/campaign_fixture.h"
#include "tests/surrogate/test_dir.h"

namespace {

namespace fs = std::filesystem;
using namespace flume::surrogate;

// Three levels of x ~ U(0,1)^3 with u_i = sqrt(2) cos(2 pi x_i): mean 0, variance 1, independent, E[u^3] = 0,
// E[u^4] = 3/2 (so u^2 - 1 has variance 1/2 and no correlation with any u_j):
//   Y1 = 1 + u1 + 0.5 u2 + 0.3 u3        mean 1, variance 1.34
//   Y2 = 1 + 2 (u1 + 0.5 u2)             variance 5, Cov(Y1, Y2) = 2.5
//   Y3 = 3 - 0.5 u1 + 0.2 (u1^2 - 1)     variance 0.27, Cov(Y1, Y3) = -0.5 (negative: a negative weight)
double u(double x) { return std::numbers::sqrt2 * std::cos(2 * std::numbers::pi * x); }
double y1(const double* x) { return 1 + u(x[0]) + 0.5 * u(x[1]) + 0.3 * u(x[2]); }
double y2(const double* x) { return 1 + 2 * (u(x[0]) + 0.5 * u(x[1])); }
double y3(const double* x) { return 3 - 0.5 * u(x[0]) + 0.2 * (u(x[0]) * u(x[0]) - 1); }
const std::vector<double> kSigma3 = {std::sqrt(1.34), std::sqrt(5.0), std::sqrt(0.27)};
const std::vector<double> kRho3 = {1.0, 2.5 / std::sqrt(1.34 * 5.0), -0.5 / std::sqrt(1.34 * 0.27)};
const std::vector<double> kCost3 = {1.0, 0.1, 0.01};

// Forrester, Sobester & Keane (2007) pair, x ~ U(0, 1); moments by composite Simpson (2e5 intervals: errors
// far below the test tolerances).
double f_high(double x) { return std::pow(6 * x - 2, 2) * std::sin(12 * x - 4); }
double f_low(double x) { return 0.5 * f_high(x) + 10 * (x - 0.5) - 5; }
double simpson(const std::function<double(double)>& f) {
  const int n = 200000;
  double s = f(0) + f(1);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4 : 2) * f(static_cast<double>(i) / n);
  return s / (3.0 * n);
}
struct Moments {
  double mean_h, sigma_h, sigma_l, cov;
};
Moments forrester() {
  Moments m;
  m.mean_h = simpson(f_high);
  const double mean_l = simpson(f_low);
  m.sigma_h = std::sqrt(simpson([&](double x) { return std::pow(f_high(x) - m.mean_h, 2); }));
  m.sigma_l = std::sqrt(simpson([&](double x) { return std::pow(f_low(x) - mean_l, 2); }));
  m.cov = simpson([&](double x) { return (f_high(x) - m.mean_h) * (f_low(x) - mean_l); });
  return m;
}

// Nested samples of the three levels: the first n[k-1] points of level k are those of level k - 1.
MfmcSamples three_levels(std::mt19937_64& rng, const std::vector<std::size_t>& n) {
  std::uniform_real_distribution<double> U(0, 1);
  MfmcSamples s;
  s.y.resize(3);
  s.cost_s = kCost3;
  for (std::size_t i = 0; i < n[2]; ++i) {
    const double x[3] = {U(rng), U(rng), U(rng)};
    if (i < n[0]) s.y[0].push_back(y1(x));
    if (i < n[1]) s.y[1].push_back(y2(x));
    s.y[2].push_back(y3(x));
  }
  return s;
}

double sample_variance(const std::vector<double>& v, double* mean_out = nullptr) {
  double mean = 0, var = 0;
  for (double e : v) mean += e / v.size();
  for (double e : v) var += (e - mean) * (e - mean) / (v.size() - 1);
  if (mean_out) *mean_out = mean;
  return var;
}

// R repetitions estimate a variance to a relative standard deviation of sqrt(2 / (R - 1)) (near-normal
// estimates); the tests allow 4 of them.
constexpr int kRepeats = 4000;
const double kTol = 4 * std::sqrt(2.0 / (kRepeats - 1));  // 0.089

// The exact weights fixed: the spread of the estimate over independent repetitions against Lemma 3.3 with the
// exact sigma and rho. The correction terms remove 85 % of sigma_1^2 / N_1 here, so a formula without them,
// or with the cross term's sign flipped, misses by far more than the tolerance (asserted).
TEST(Mfmc, VarianceFormulaMatchesRepeatedEstimatesThreeLevels) {
  const std::vector<std::size_t> n = {20, 120, 640};
  const std::vector<double> nd(n.begin(), n.end());
  std::vector<double> alpha(3);
  for (int k = 0; k < 3; ++k) alpha[k] = kRho3[k] * kSigma3[0] / kSigma3[k];
  std::mt19937_64 rng(3);
  std::vector<double> estimates;
  for (int r = 0; r < kRepeats; ++r) estimates.push_back(mfmc_estimate(three_levels(rng, n), 0.95, alpha).mean);
  double mean = 0;
  const double spread = sample_variance(estimates, &mean);
  const double predicted = mfmc_variance(nd, alpha, kSigma3, kRho3);
  std::printf("three levels, exact weights: spread %.5g, Lemma 3.3 %.5g, plain MC %.5g\n", spread, predicted,
              kSigma3[0] * kSigma3[0] / n[0]);
  EXPECT_NEAR(spread / predicted, 1.0, kTol);
  EXPECT_NEAR(mean, 1.0, 4 * std::sqrt(spread / kRepeats));
  EXPECT_LT(predicted, 0.5 * kSigma3[0] * kSigma3[0] / n[0]);
  std::vector<double> flipped_rho = {1.0, -kRho3[1], -kRho3[2]};
  EXPECT_GT(mfmc_variance(nd, alpha, kSigma3, flipped_rho) / spread, 1 + 3 * kTol);
}

// The estimator as `flume surrogate multilevel` uses it: weights and statistics estimated from the N_1 common
// points. The weights' error adds about sum_k (1/N_{k-1} - 1/N_k) sigma_1^2 (1 - rho_1k^2) / N_1 to the variance
// (a regression slope's variance times sigma_k^2), which the tolerance adds to the repetitions'.
TEST(Mfmc, EstimatedWeightsPlugInVarianceMatchesRepeatedEstimates) {
  const std::vector<std::size_t> n = {40, 240, 1280};
  std::mt19937_64 rng(5);
  std::vector<double> estimates;
  double predicted = 0;
  for (int r = 0; r < kRepeats; ++r) {
    const auto e = mfmc_estimate(three_levels(rng, n));
    estimates.push_back(e.mean);
    predicted += e.variance / kRepeats;
  }
  double mean = 0;
  const double spread = sample_variance(estimates, &mean);
  double excess = 0;
  for (int k = 1; k < 3; ++k)
    excess += (1.0 / n[k - 1] - 1.0 / n[k]) * kSigma3[0] * kSigma3[0] * (1 - kRho3[k] * kRho3[k]) / n[0];
  std::printf("three levels, estimated weights: spread %.5g, mean plug-in formula %.5g, weights' excess %.3g\n",
              spread, predicted, excess);
  EXPECT_NEAR(spread / predicted, 1.0, kTol + excess / predicted);
  EXPECT_NEAR(mean, 1.0, 4 * std::sqrt(spread / kRepeats));
}

// Two levels with unit weight: the estimate is Giles' two-level one with its level-0 mean over all N_2 low runs
// (the paired ones too), and as the pairs then enter both terms its variance is Giles' V0/N_2 + V1/N_1 plus
// 2 (Cov(Y_H, Y_L) - Var Y_L) / N_2. The Forrester pair's repetitions tell the two formulas apart.
TEST(Mfmc, UnitWeightTwoLevelsIsGilesWithTheLowMeanOverAllLowRuns) {
  const Moments m = forrester();
  const std::size_t n1 = 20, n2 = 40;  // few low-only runs: the pairs weigh in the low mean
  const std::vector<double> nd = {double(n1), double(n2)}, unit = {1.0, 1.0};
  const std::vector<double> sigma = {m.sigma_h, m.sigma_l}, rho = {1.0, m.cov / (m.sigma_h * m.sigma_l)};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<double> estimates;
  for (int r = 0; r < kRepeats; ++r) {
    MfmcSamples s;
    s.y.resize(2);
    s.cost_s = {10.0, 1.0};
    TwoLevelSamples g;
    g.cost_high_s = 10.0;
    g.cost_low_s = 1.0;
    for (std::size_t i = 0; i < n2; ++i) {
      const double x = U(rng);
      if (i < n1) s.y[0].push_back(f_high(x)), g.pair_high.push_back(f_high(x)), g.pair_low.push_back(f_low(x));
      s.y[1].push_back(f_low(x));
      g.low_only.push_back(f_low(x));
    }
    const auto e = mfmc_estimate(s, 0.95, unit);
    if (r < 20) {
      EXPECT_NEAR(e.mean, two_level_estimate(g).mean, 1e-12 * std::abs(m.mean_h) + 1e-12);
    }
    estimates.push_back(e.mean);
  }
  double mean = 0;
  const double spread = sample_variance(estimates, &mean);
  const double lemma = mfmc_variance(nd, unit, sigma, rho);
  const double v0 = m.sigma_l * m.sigma_l, v1 = m.sigma_h * m.sigma_h + v0 - 2 * m.cov;
  const double giles_independent = v0 / n2 + v1 / n1;
  std::printf("Forrester unit weights: spread %.5g, Lemma 3.3 %.5g, Giles' independent-sample formula %.5g\n",
              spread, lemma, giles_independent);
  EXPECT_NEAR(lemma, giles_independent + 2 * (m.cov - v0) / n2, 1e-12 * lemma);
  EXPECT_NEAR(spread / lemma, 1.0, kTol);
  EXPECT_GT(std::abs(spread / giles_independent - 1), kTol);
  EXPECT_NEAR(mean, m.mean_h, 4 * std::sqrt(spread / kRepeats));
}

// alpha_k = rho_1k sigma_1 / sigma_k is Cov(Y_1, Y_k) / Var(Y_k), the least-squares slope of Y_1 on Y_k over the
// common points, and the variance (Lemma 3.3, same statistics) is smallest there.
TEST(Mfmc, OptimalWeightIsTheRegressionSlopeAndMinimisesTheVariance) {
  std::mt19937_64 rng(17);
  const MfmcSamples s = three_levels(rng, {30, 200, 900});
  const auto e = mfmc_estimate(s);
  for (int k = 1; k < 3; ++k) {
    double m1 = 0, mk = 0, sxy = 0, sxx = 0;
    for (int i = 0; i < 30; ++i) m1 += s.y[0][i] / 30, mk += s.y[k][i] / 30;
    for (int i = 0; i < 30; ++i) sxy += (s.y[k][i] - mk) * (s.y[0][i] - m1), sxx += std::pow(s.y[k][i] - mk, 2);
    EXPECT_NEAR(e.levels[k].alpha, sxy / sxx, 1e-10 * std::abs(sxy / sxx));
    for (double d : {-0.05, 0.05}) {
      std::vector<double> a = {1.0, e.levels[1].alpha, e.levels[2].alpha};
      a[k] += d * std::abs(a[k]);
      EXPECT_GT(mfmc_estimate(s, 0.95, a).variance, e.variance);
    }
  }
  EXPECT_LT(e.levels[2].alpha, 0);  // Y3 falls as Y1 rises
}

// Theorem 3.4: for a budget p, N_1 = p / sum_k c_k r_k and N_k = r_k N_1 give the variance of Corollary 3.5,
// sigma_1^2 / p (sum_k sqrt(c_k (rho_1k^2 - rho_1,k+1^2)))^2, through Lemma 3.3, and other allocations of the
// same budget give more.
TEST(Mfmc, OptimalAllocationMinimisesTheVarianceForABudget) {
  const std::vector<std::size_t> all = {0, 1, 2};
  std::string why;
  const auto r = mfmc_optimal_ratios(kCost3, kRho3, all, &why);
  ASSERT_EQ(r.size(), 3u) << why;
  std::vector<double> alpha(3);
  for (int k = 0; k < 3; ++k) alpha[k] = kRho3[k] * kSigma3[0] / kSigma3[k];
  auto variance_at = [&](const std::vector<double>& ratio, double budget) {
    double per = 0;
    for (int k = 0; k < 3; ++k) per += kCost3[k] * ratio[k];
    std::vector<double> n(3);
    for (int k = 0; k < 3; ++k) n[k] = ratio[k] * budget / per;
    return mfmc_variance(n, alpha, kSigma3, kRho3);
  };
  const double budget = 100, best = variance_at(r, budget);
  const double ratio = mfmc_optimal_cost_ratio(kCost3, kRho3, all);
  EXPECT_NEAR(kSigma3[0] * kSigma3[0] * kCost3[0] / budget / best, ratio, 1e-10 * ratio);
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> f(0.7, 1.4);
  for (int t = 0; t < 200; ++t) {
    std::vector<double> other = {1.0, r[1] * f(rng), r[2] * f(rng)};
    if (other[2] < other[1]) continue;  // not nested
    EXPECT_GT(variance_at(other, budget), best);
  }
  // Two levels: the same ratio as c_1 / (sqrt(c_1 (1 - rho^2)) + sqrt(c_2 rho^2))^2.
  const std::vector<double> c2 = {1.0, 0.1}, rho2 = {1.0, 0.9};
  EXPECT_NEAR(mfmc_optimal_cost_ratio(c2, rho2, {0, 1}), 1 / std::pow(std::sqrt(0.19) + std::sqrt(0.081), 2), 1e-12);
}

// The ordering conditions of Theorem 3.4 and the subset chosen when they fail (Algorithm 1).
TEST(Mfmc, OrderingFailuresAreNamedAndTheBestOrderedSubsetChosen) {
  std::string why;
  // |rho| must fall with the level.
  EXPECT_TRUE(mfmc_optimal_ratios({1, 0.1, 0.01}, {1, 0.8, 0.9}, {0, 1, 2}, &why).empty());
  EXPECT_NE(why.find("|rho| of level 3"), std::string::npos) << why;
  // c_2 / c_3 = 2 but (0.81 - 0.09) / 0.09 = 8 is needed.
  EXPECT_TRUE(mfmc_optimal_ratios({1, 0.1, 0.05}, {1, 0.9, 0.3}, {0, 1, 2}, &why).empty());
  EXPECT_NE(why.find("levels 2 and 3"), std::string::npos) << why;
  EXPECT_EQ(mfmc_optimal_ratios({1, 0.1, 0.05}, {1, 0.9, 0.3}, {0, 1}).size(), 2u);
  // The estimator on levels given in the wrong order (Y3 before Y2): not ordered, and the ratio is the best of
  // the ordered subsets, found here by hand.
  std::mt19937_64 rng(29);
  MfmcSamples s = three_levels(rng, {50, 300, 2000});
  std::swap(s.y[1], s.y[2]);
  s.y[1].resize(300);
  s.cost_s = {1.0, 0.1, 0.01};
  const auto e = mfmc_estimate(s);
  EXPECT_FALSE(e.ordered);
  EXPECT_FALSE(e.ordering_note.empty());
  std::vector<double> rho = {1.0, e.levels[1].rho, e.levels[2].rho};
  double best = 1;
  for (const std::vector<std::size_t>& sub : {std::vector<std::size_t>{0, 1}, {0, 2}, {0, 1, 2}})
    if (!mfmc_optimal_ratios(s.cost_s, rho, sub).empty()) best = std::max(best, mfmc_optimal_cost_ratio(s.cost_s, rho, sub));
  EXPECT_DOUBLE_EQ(e.optimal_cost_ratio, best);
  EXPECT_GT(best, 1.0);
}

// From a store: three campaigns of one seed's Monte Carlo points (drawn point by point, so nested), 12 / 60 / 400
// runs; the levels nest, the unit-weight and optimal estimates hold the exact mean, and the command prints both
// (three levels by --levels; two by the old --low/--high form, with the Giles lines).
TEST(Mfmc, NestsCampaignsOfAStoreAndTheCommandPrintsBoth) {
  const fs::path dir = flume::test::surrogate_test_dir();
  const std::string db = (dir / "s.db").string();
  auto spec = [](const std::string& name, int n) {
    std::string p;
    for (const char* x : {"x1", "x2", "x3"})
      p += std::string(p.empty() ? "" : ",") + R"({"path": ")" + x +
           R"(", "distribution": {"type": "uniform", "lower": 0, "upper": 1}})";
    return R"({"name": ")" + name + R"(", "model": "ishigami", "parameters": [)" + p +
           R"(], "design": {"type": "monte_carlo", "samples": )" + std::to_string(n) + R"(}, "seed": 7})";
  };
  std::map<double, double> y2_at_y1;  // the value each point gives, to check the nesting
  auto level = [&](const std::string& name, int n, double (*f)(const double*)) {
    flume::test::make_campaign(db, spec(name, n), [&, f](const std::vector<double>& x, std::int64_t) {
      if (f == y1) y2_at_y1[y1(x.data())] = y2(x.data());
      return flume::test::ok_outcome({{"y", f(x.data())}});
    });
  };
  level("top", 12, y1);
  level("mid", 60, y2);
  level("low", 400, y3);
  const auto s = load_levels(db, {"top", "mid", "low"}, "y", {1.0, 0.1, 0.01});
  ASSERT_EQ(s.y[0].size(), 12u);
  ASSERT_EQ(s.y[1].size(), 60u);
  ASSERT_EQ(s.y[2].size(), 400u);
  for (int i = 0; i < 12; ++i) EXPECT_DOUBLE_EQ(s.y[1][i], y2_at_y1.at(s.y[0][i]));
  const auto e = mfmc_estimate(s, 0.999);
  EXPECT_LE(e.lo, 1.0);
  EXPECT_GE(e.hi, 1.0);
  EXPECT_DOUBLE_EQ(e.cost_s, 12 * 1.0 + 60 * 0.1 + 400 * 0.01);

  auto flume = [&](std::vector<std::string> args) {
    args.insert(args.begin(), FLUME_EXE);
    return flume::test::run_command(args, dir, 110);
  };
  auto r = flume({"surrogate", "multilevel", "--db", db, "--levels", "top,mid,low", "--metric", "y", "--cost",
                  "1,0.1,0.01"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("MFMC, optimal weights of E[y]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("MFMC, unit weights of E[y]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("3,low,400,0.01"), std::string::npos) << r.out;
  r = flume({"surrogate", "multilevel", "--db", db, "--low", "mid", "--high", "top", "--metric", "y", "--cost-low",
             "0.1", "--cost-high", "1"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("two-level Monte Carlo (Giles 2008)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("MFMC, optimal weights"), std::string::npos) << r.out;
  // Equal sizes: no low-only run for Giles' first term (said), the MFMC correction is zero.
  level("mid12", 12, y2);
  r = flume({"surrogate", "multilevel", "--db", db, "--levels", "top,mid12", "--metric", "y", "--cost", "1,0.1"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("not defined, 0 low-only run(s)"), std::string::npos) << r.out;
  r = flume({"surrogate", "multilevel", "--db", db, "--levels", "top,mid", "--metric", "y", "--cost", "1"});
  EXPECT_NE(r.rc, 0);
  EXPECT_NE(r.err.find("--cost"), std::string::npos) << r.err;
  r = flume({"surrogate", "multilevel", "--db", db, "--levels", "top,nosuch", "--metric", "y"});
  EXPECT_NE(r.rc, 0);
  EXPECT_NE(r.err.find("nosuch"), std::string::npos) << r.err;
}

}  // namespace
