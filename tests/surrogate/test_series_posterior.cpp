// The calibration posterior on a series emulator (surrogate/series_posterior.h) against analytic posteriors:
// a series linear in the parameters, whose posterior is Gaussian and known, and a pulse the emulator cannot
// follow from a coarse design, where only its own error variance keeps the interval honest.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "linear_gaussian.h"
#include "surrogate/series_posterior.h"

namespace {

using namespace flume::surrogate;

// Thinned draws of the chain: mean, standard deviation and correlation of the two parameters.
struct DrawStats {
  double mean[2] = {0, 0}, sd[2] = {0, 0}, corr = 0;
};
DrawStats draw_stats(const std::vector<std::vector<double>>& x) {
  DrawStats s;
  const double n = static_cast<double>(x.size());
  for (const auto& v : x)
    for (int j = 0; j < 2; ++j) s.mean[j] += v[j] / n;
  double c = 0;
  for (const auto& v : x) {
    for (int j = 0; j < 2; ++j) s.sd[j] += (v[j] - s.mean[j]) * (v[j] - s.mean[j]) / (n - 1);
    c += (v[0] - s.mean[0]) * (v[1] - s.mean[1]) / (n - 1);
  }
  for (int j = 0; j < 2; ++j) s.sd[j] = std::sqrt(s.sd[j]);
  s.corr = c / (s.sd[0] * s.sd[1]);
  return s;
}

// The series y_k = a + b t_k at 50 times, its target at (1, 2) plus N(0, 0.1^2): under a flat prior the
// posterior is Gaussian, least-squares mean, covariance sigma^2 (X^T X)^-1. The emulator is exact here (two
// components, each linear in the parameters, which the quadratic trend holds), so its error variance is
// nil and the chain must reproduce the analytic posterior within its Monte Carlo error.
TEST(SeriesPosterior, LinearSeriesHasTheAnalyticPosterior) {
  const flume::test::LinearGaussian g = flume::test::linear_gaussian(50, 0.1);
  const int n = g.n;
  const double sigma = g.sigma, corr = g.corr;
  const std::vector<double>& t = g.t;
  const std::vector<double>& y = g.y;
  const double* mean = g.mean;
  const double* sd = g.sd;
  SeriesData d;
  d.names = {"a", "b"};
  d.lower = {0, 1};
  d.upper = {2, 3};
  d.n_residuals = n;
  auto add = [&](double a, double b) {
    d.points.push_back({a, b});
    std::vector<double> r(n);
    for (int i = 0; i < n; ++i) r[i] = a + b * t[i] - y[i];
    d.residuals.push_back(r);
  };
  // As an optimizer and its profile leave them: a coarse grid over the bounds, a finer one round the optimum.
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j <= 4; ++j) add(0.5 * i, 1 + 0.5 * j);
  for (int i = -3; i <= 3; ++i)
    for (int j = -3; j <= 3; ++j) add(mean[0] + 1.5 * i * sd[0], mean[1] + 1.5 * j * sd[1]);
  PosteriorSettings s;
  s.noise_m = sigma;
  s.samples = 100000;
  s.draws = 1000;
  const Posterior p = series_posterior(d, s);
  ASSERT_EQ(p.parameters.size(), 2u);
  EXPECT_EQ(p.components, 2u) << "a series linear in two parameters spans two directions";
  EXPECT_GT(p.q2, 1 - 1e-9);
  EXPECT_LT(p.emulator_rms, 1e-6 * sigma);
  // Monte Carlo error: the 1,000 draws, 100 chain steps apart, are taken as independent (a random walk in two
  // dimensions forgets its start within some tens of steps), so the chain is worth at least 1,000
  // independent samples. Standard errors for N = 1,000: the mean sd / sqrt(N) = 0.032 sd; the sd
  // 1 / sqrt(2 (N - 1)) = 2.2 %; the correlation (1 - rho^2) / sqrt(N); a 2.5 % or 97.5 % quantile
  // sqrt(0.025 * 0.975 / N) / phi(1.96) = 0.084 sd, so the 95 % width (3.92 sd) to sqrt(2) 0.084 / 3.92 = 3.0
  // %. Each is asserted to 4 standard errors.
  const double N = 1000;
  const DrawStats ds = draw_stats(p.draws);
  for (int j = 0; j < 2; ++j) {
    const auto& q = p.parameters[j];
    std::printf("%s: mean %.4f, 95 %% [%.4f, %.4f]; analytic %.4f +- %.4f; draws sd %.4f (analytic %.4f)\n",
                q.name.c_str(), q.mean, q.lo, q.hi, mean[j], 1.959964 * sd[j], ds.sd[j], sd[j]);
    EXPECT_NEAR(q.mean, mean[j], 4 * sd[j] / std::sqrt(N)) << q.name;
    EXPECT_NEAR(ds.mean[j], mean[j], 4 * sd[j] / std::sqrt(N)) << q.name;
    EXPECT_NEAR(ds.sd[j] / sd[j], 1.0, 4 / std::sqrt(2 * (N - 1))) << q.name;
    EXPECT_NEAR((q.hi - q.lo) / (2 * 1.959964 * sd[j]), 1.0, 4 * std::sqrt(2.0) * 0.084 / 3.92) << q.name;
  }
  std::printf("correlation %.4f (analytic %.4f), acceptance %.2f\n", ds.corr, corr, p.acceptance);
  EXPECT_NEAR(ds.corr, corr, 4 * (1 - corr * corr) / std::sqrt(N));
  // Half the noise, half the width: the ratio of two widths, each to 3.0 %, is known to sqrt(2) 3.0 % (4 of
  // those asserted; the two chains share their random numbers, which only narrows the error).
  s.noise_m = sigma / 2;
  const Posterior half = series_posterior(d, s);
  for (int j = 0; j < 2; ++j)
    EXPECT_NEAR((half.parameters[j].hi - half.parameters[j].lo) / (p.parameters[j].hi - p.parameters[j].lo),
                0.5, 0.5 * 4 * std::sqrt(2.0) * std::sqrt(2.0) * 0.084 / 3.92);
}

// A Gaussian pulse eta = h exp(-((t - c) / w)^2), w = 0.1 s, recorded at 101 times with 1 cm of noise; the
// target at c = 1 s, h = 1 m. Ten evaluations scattered as a Latin hypercube over c in [0.75, 1.25] and h in
// [0.85, 1.15], 0.05 s apart in c (the truth halfway between two), too few for the emulator to follow the
// pulse between them: its leave-one-out error is large where the pulse passes. With that error in the
// likelihood the 95 % interval must hold the truth; without it the chain trusts the emulator's series as if
// exact, and its interval, a fraction of the spacing wide, misses.
TEST(SeriesPosterior, EmulatorErrorKeepsTheIntervalHonest) {
  const int n = 101, N = 10;
  const double sigma = 0.01, w = 0.1, c0 = 1.0, h0 = 1.0;
  std::vector<double> t(n), target(n);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0, sigma);
  auto pulse = [&](double c, double h, double tk) { return h * std::exp(-std::pow((tk - c) / w, 2)); };
  for (int i = 0; i < n; ++i) {
    t[i] = 2.0 * i / (n - 1.0);
    target[i] = pulse(c0, h0, t[i]) + noise(rng);
  }
  SeriesData d;
  d.names = {"c", "h"};
  d.lower = {0.5, 0.5};
  d.upper = {1.5, 1.5};
  d.n_residuals = n;
  for (int i = 0; i < N; ++i) {
    const double c = 0.75 + 0.5 * (i + 0.5) / N, h = 0.85 + 0.3 * ((3 * i) % N + 0.5) / N;
    d.points.push_back({c, h});
    std::vector<double> r(n);
    for (int k = 0; k < n; ++k) r[k] = pulse(c, h, t[k]) - target[k];
    d.residuals.push_back(r);
  }
  PosteriorSettings s;
  s.noise_m = sigma;
  const Posterior honest = series_posterior(d, s);
  s.emulator_error = false;
  const Posterior naive = series_posterior(d, s);
  const double truth[2] = {c0, h0};
  bool naive_holds = true;
  for (int j = 0; j < 2; ++j) {
    const auto &a = honest.parameters[j], &b = naive.parameters[j];
    std::printf(
        "%s: with the emulator's error [%.4f, %.4f], without [%.4f, %.4f], truth %.2f (Q2 %.3f, error "
        "RMS %.4f m)\n",
        a.name.c_str(), a.lo, a.hi, b.lo, b.hi, truth[j], honest.q2, honest.emulator_rms);
    EXPECT_LE(a.lo, truth[j]) << a.name;
    EXPECT_GE(a.hi, truth[j]) << a.name;
    naive_holds = naive_holds && b.lo <= truth[j] && truth[j] <= b.hi;
  }
  EXPECT_GT(honest.emulator_rms, sigma) << "the design is meant to be too coarse for the emulator";
  EXPECT_FALSE(naive_holds)
      << "without its error the emulator's interval should miss: the test shows nothing";
}

}  // namespace
