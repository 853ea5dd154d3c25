// Statistics of one scalar output over the runs of a campaign, each with a confidence interval. The samples
// are taken as independent draws from the output's distribution (true for Monte Carlo designs and for the
// A and B blocks of a Saltelli design; conservative for LHS and randomised Sobol' designs).
//   mean:       Student t interval, mean +- t_{n-1} s / sqrt(n)
//   std:        percentile bootstrap
//   quantiles:  distribution-free order-statistic interval [X_(l), X_(u)] from Binomial(n, p)
//   P(Y > t):   Clopper-Pearson (exact binomial) interval
//   CDF:        empirical CDF with a simultaneous bootstrap band F_n +- d, d the (1 - alpha) bootstrap
//               quantile of sup |F*_n - F_n|
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace flume::report {

struct Interval {
  double lo = 0, hi = 0;
};
struct Estimate {
  double value = 0;
  Interval ci;
};

struct StatsOptions {
  double confidence = 0.95;
  std::size_t bootstrap = 1000;  // resamples
  std::uint64_t seed = 1;
};

struct QuantileEstimate {
  double p = 0;
  Estimate q;
  bool ci_open =
      false;  // too few runs for an interval of the asked level: the bounds are the sample extremes
};

struct Exceedance {
  double threshold = 0;
  std::size_t count = 0;  // runs above the threshold
  Estimate p;
};

struct Summary {
  std::size_t n = 0;
  double min = 0, max = 0;
  Estimate mean, std;
  std::vector<QuantileEstimate> quantiles;  // 5 %, 50 %, 95 %
  std::vector<Exceedance> exceedances;
};

// n >= 2 finite values; throws std::invalid_argument otherwise.
Summary summarize(const std::vector<double>& x, const std::vector<double>& thresholds,
                  const StatsOptions& opt);

// Order-statistic confidence interval of the p-quantile: 1-based ranks (l, u) with
// P(l <= K < u) >= confidence for K ~ Binomial(n, p); clamped to [1, n] (open = true when clamped).
struct RankInterval {
  std::size_t l = 1, u = 1;
  bool open = false;
};
RankInterval quantile_ranks(std::size_t n, double p, double confidence);

// Clopper-Pearson interval of a binomial proportion k / n.
Interval clopper_pearson(std::size_t k, std::size_t n, double confidence);

struct EcdfBand {
  std::vector<double> x;          // sorted sample
  std::vector<double> f, lo, hi;  // F_n(x_i) = i / n (1-based i) and the band
  double half_width = 0;
};
EcdfBand ecdf_band(const std::vector<double>& x, const StatsOptions& opt);

// Running mean of x[0..k] for k = 1..n-1 with its Student interval (k >= 2 points).
struct RunningMean {
  std::vector<double> n, mean, lo, hi;
};
RunningMean running_mean(const std::vector<double>& x, double confidence);

// Runs for which the Student interval of the mean is `width` wide at the sample's standard deviation:
// the smallest n with 2 t_{n-1} s / sqrt(n) <= width, at most kMaxRunsNeeded.
inline constexpr double kMaxRunsNeeded = 1e15;
std::size_t runs_for_width(double std, double width, double confidence);

}  // namespace flume::report
