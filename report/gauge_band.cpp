#include "report/gauge_band.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace flume::report {
namespace {

// The record's value at time t by linear interpolation; NaN outside its span or across a non-finite sample.
double value_at(const TimeSeries& r, double t) {
  if (r.time.empty() || t < r.time.front() || t > r.time.back()) return std::numeric_limits<double>::quiet_NaN();
  const auto it = std::lower_bound(r.time.begin(), r.time.end(), t);
  const std::size_t i = static_cast<std::size_t>(it - r.time.begin());
  if (r.time[i] == t) return r.value[i];
  const double w = (t - r.time[i - 1]) / (r.time[i] - r.time[i - 1]);
  return (1 - w) * r.value[i - 1] + w * r.value[i];
}

}  // namespace

double sample_quantile(std::vector<double>& values, double p) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double h = p * static_cast<double>(values.size() - 1);
  const std::size_t k = static_cast<std::size_t>(std::floor(h));
  if (k + 1 >= values.size()) return values.back();
  return values[k] + (h - static_cast<double>(k)) * (values[k + 1] - values[k]);
}

GaugeBand gauge_band(const std::vector<TimeSeries>& records, double level) {
  GaugeBand b;
  if (records.empty()) return b;
  const double a = (1 - level) / 2;
  std::vector<double> at;
  for (double t : records.front().time) {
    at.clear();
    for (const TimeSeries& r : records) {
      const double v = value_at(r, t);
      if (std::isfinite(v)) at.push_back(v);
    }
    b.time.push_back(t);
    b.lo.push_back(sample_quantile(at, a));
    b.median.push_back(sample_quantile(at, 0.5));
    b.hi.push_back(sample_quantile(at, 1 - a));
  }
  return b;
}

}  // namespace flume::report
