// Confidence intervals by OpenTURNS' distribution functions (Student, Beta, Binomial) and by resampling.
#include "report/statistics.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <openturns/OT.hxx>
#include <random>
#include <stdexcept>

namespace flume::report {
namespace {

double sample_std(const std::vector<double>& x) {
  const double m = std::accumulate(x.begin(), x.end(), 0.0) / x.size();
  double s = 0;
  for (double v : x) s += (v - m) * (v - m);
  return std::sqrt(s / (x.size() - 1));
}

OT::Sample to_sample(const std::vector<double>& x) {
  OT::Sample s(x.size(), 1);
  for (std::size_t i = 0; i < x.size(); ++i) s(i, 0) = x[i];
  return s;
}

// Percentile of a bootstrap replicate set (sorted in place).
Interval percentile_interval(std::vector<double>& reps, double confidence) {
  std::sort(reps.begin(), reps.end());
  const double a = (1 - confidence) / 2;
  const OT::Sample s = to_sample(reps);
  return {s.computeQuantilePerComponent(a)[0], s.computeQuantilePerComponent(1 - a)[0]};
}

}  // namespace

RankInterval quantile_ranks(std::size_t n, double p, double confidence) {
  // K ~ Bin(n, p) counts the sample points below the true quantile; X_(l) <= q < X_(u) iff l <= K < u.
  // l: the largest rank with P(K <= l - 1) <= a; u: the smallest with P(K <= u - 1) >= 1 - a. The CDF is
  // monotone, so each search starts at the normal approximation and walks to the exact rank.
  const OT::Binomial bin(n, p);
  const double a = (1 - confidence) / 2;
  auto cdf = [&](long k) { return k < 0 ? 0.0 : bin.computeCDF(static_cast<double>(k)); };
  const double mid = n * p, sd = std::sqrt(n * p * (1 - p)), z = OT::DistFunc::qNormal(1 - a);
  const long ln = static_cast<long>(n);
  long l = std::clamp(static_cast<long>(std::floor(mid - z * sd)), 0L, ln);
  while (l > 0 && cdf(l - 1) > a) --l;
  while (l < ln && cdf(l) <= a) ++l;  // cdf(l) is P(K <= (l + 1) - 1)
  long u = std::clamp(static_cast<long>(std::ceil(mid + z * sd)), 1L, ln + 1);
  while (u <= ln && cdf(u - 1) < 1 - a) ++u;
  while (u > 1 && cdf(u - 2) >= 1 - a) --u;
  RankInterval r;
  r.open = l < 1 || u > ln;
  r.l = static_cast<std::size_t>(std::max(l, 1L));
  r.u = static_cast<std::size_t>(std::min(u, ln));
  return r;
}

Interval clopper_pearson(std::size_t k, std::size_t n, double confidence) {
  const double a = (1 - confidence) / 2;
  Interval ci;
  ci.lo = k == 0 ? 0.0 : OT::DistFunc::qBeta(static_cast<double>(k), static_cast<double>(n - k + 1), a);
  ci.hi = k == n ? 1.0 : OT::DistFunc::qBeta(static_cast<double>(k + 1), static_cast<double>(n - k), 1 - a);
  return ci;
}

Summary summarize(const std::vector<double>& x_in, const std::vector<double>& thresholds,
                  const StatsOptions& opt) {
  std::vector<double> x;
  for (double v : x_in)
    if (std::isfinite(v)) x.push_back(v);
  if (x.size() < 2) throw std::invalid_argument("statistics need at least 2 finite values");
  Summary s;
  s.n = x.size();
  const double n = static_cast<double>(x.size());
  std::vector<double> sorted = x;
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();

  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double sd = sample_std(x);
  const double t = OT::DistFunc::qStudent(n - 1, 1 - (1 - opt.confidence) / 2);
  s.mean = {mean, {mean - t * sd / std::sqrt(n), mean + t * sd / std::sqrt(n)}};

  std::mt19937_64 rng(opt.seed);
  std::uniform_int_distribution<std::size_t> pick(0, x.size() - 1);
  std::vector<double> reps, resample(x.size());
  for (std::size_t b = 0; b < opt.bootstrap; ++b) {
    for (auto& v : resample) v = x[pick(rng)];
    reps.push_back(sample_std(resample));
  }
  s.std = {sd, opt.bootstrap ? percentile_interval(reps, opt.confidence) : Interval{sd, sd}};

  const OT::Sample sample = to_sample(sorted);
  for (double p : {0.05, 0.5, 0.95}) {
    QuantileEstimate q;
    q.p = p;
    q.q.value = sample.computeQuantilePerComponent(p)[0];
    const RankInterval r = quantile_ranks(x.size(), p, opt.confidence);
    q.q.ci = {sorted[r.l - 1], sorted[r.u - 1]};
    q.ci_open = r.open;
    s.quantiles.push_back(q);
  }
  for (double th : thresholds) {
    Exceedance e;
    e.threshold = th;
    e.count = static_cast<std::size_t>(std::count_if(x.begin(), x.end(), [th](double v) { return v > th; }));
    e.p = {e.count / n, clopper_pearson(e.count, x.size(), opt.confidence)};
    s.exceedances.push_back(e);
  }
  return s;
}

EcdfBand ecdf_band(const std::vector<double>& x_in, const StatsOptions& opt) {
  EcdfBand band;
  for (double v : x_in)
    if (std::isfinite(v)) band.x.push_back(v);
  std::sort(band.x.begin(), band.x.end());
  const std::size_t n = band.x.size();
  if (n == 0) return band;
  for (std::size_t i = 0; i < n; ++i) band.f.push_back(static_cast<double>(i + 1) / n);
  // sup |F*_n - F_n| over the sample points (both are step functions jumping only there).
  std::mt19937_64 rng(opt.seed + 7);
  std::uniform_int_distribution<std::size_t> pick(0, n - 1);
  std::vector<double> sups, star(n);
  for (std::size_t b = 0; b < opt.bootstrap; ++b) {
    for (auto& v : star) v = band.x[pick(rng)];
    std::sort(star.begin(), star.end());
    double sup = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double f_star =
          static_cast<double>(std::upper_bound(star.begin(), star.end(), band.x[i]) - star.begin()) / n;
      sup = std::max(sup, std::abs(f_star - band.f[i]));
    }
    sups.push_back(sup);
  }
  if (!sups.empty()) {
    std::sort(sups.begin(), sups.end());
    band.half_width = to_sample(sups).computeQuantilePerComponent(opt.confidence)[0];
  }
  for (double f : band.f) {
    band.lo.push_back(std::max(0.0, f - band.half_width));
    band.hi.push_back(std::min(1.0, f + band.half_width));
  }
  return band;
}

RunningMean running_mean(const std::vector<double>& x, double confidence) {
  RunningMean r;
  double sum = 0, sum2 = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sum += x[k];
    sum2 += x[k] * x[k];
    const double n = static_cast<double>(k + 1);
    if (k == 0) continue;
    const double m = sum / n;
    const double var = std::max(0.0, (sum2 - n * m * m) / (n - 1));
    const double h = OT::DistFunc::qStudent(n - 1, 1 - (1 - confidence) / 2) * std::sqrt(var / n);
    r.n.push_back(n);
    r.mean.push_back(m);
    r.lo.push_back(m - h);
    r.hi.push_back(m + h);
  }
  return r;
}

std::size_t runs_for_width(double std, double width, double confidence) {
  if (!(width > 0) || !(std >= 0)) return 0;
  if (std == 0) return 2;
  const double z = OT::DistFunc::qNormal(1 - (1 - confidence) / 2);
  // Start from the normal approximation and step up until the Student interval fits. Beyond 1e15 runs the
  // answer is "never" in practice: returned as that bound (a mean near zero against its spread gave 1e25,
  // which overflowed the cast and left the loop stepping from a garbage start).
  const double normal = std::ceil(std::pow(2 * z * std / width, 2));
  if (!(normal < kMaxRunsNeeded)) return static_cast<std::size_t>(kMaxRunsNeeded);
  std::size_t n = std::max<std::size_t>(2, static_cast<std::size_t>(normal));
  while (2 * OT::DistFunc::qStudent(static_cast<double>(n - 1), 1 - (1 - confidence) / 2) * std /
             std::sqrt(static_cast<double>(n)) >
         width)
    ++n;
  return n;
}

}  // namespace flume::report
