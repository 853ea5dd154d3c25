#include "study/compare.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace flume::study {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

double interpolate_at(const Series& s, double t) {
  const auto& x = s.time;
  if (x.empty() || !(t >= x.front()) || !(t <= x.back())) return kNaN;
  const auto it = std::lower_bound(x.begin(), x.end(), t);
  const size_t k = static_cast<size_t>(it - x.begin());
  if (x[k] == t) return s.value[k];
  const double w = (t - x[k - 1]) / (x[k] - x[k - 1]);
  return s.value[k - 1] + w * (s.value[k] - s.value[k - 1]);  // NaN in, NaN out
}

double rms_difference(const Series& sim, const Series& ref, double t0, double t1) {
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < ref.time.size(); ++i) {
    const double t = ref.time[i];
    if (t < t0 || t > t1) continue;
    const double d = interpolate_at(sim, t) - ref.value[i];
    if (!std::isfinite(d)) continue;
    sum += d * d;
    ++n;
  }
  return n ? std::sqrt(sum / double(n)) : kNaN;
}

double peak_in(const Series& s, double t0, double t1) {
  double peak = kNaN;
  for (size_t i = 0; i < s.time.size(); ++i)
    if (s.time[i] >= t0 && s.time[i] <= t1 && std::isfinite(s.value[i]) && !(s.value[i] <= peak))
      peak = s.value[i];
  return peak;
}

double arrival_time(const Series& s, double threshold, double t0, double t1) {
  double start = kNaN;
  for (size_t i = 0; i < s.time.size(); ++i) {
    if (s.time[i] < t0 || s.time[i] > t1 || !std::isfinite(s.value[i])) continue;
    if (std::isnan(start)) start = s.value[i];
    if (s.value[i] >= start + threshold) return s.time[i];
  }
  return kNaN;
}

GaugeError compare_gauge(const std::string& name, const Series& sim, const Series& ref, double t0, double t1,
                         double arrival_threshold_m) {
  GaugeError e;
  e.name = name;
  e.rms_m = rms_difference(sim, ref, t0, t1);
  e.ref_peak_m = peak_in(ref, t0, t1);
  e.peak_m = peak_in(sim, t0, t1);
  e.peak_rel = (e.peak_m - e.ref_peak_m) / std::fabs(e.ref_peak_m);
  e.arrival_s = arrival_time(sim, arrival_threshold_m, t0, t1);
  e.ref_arrival_s = arrival_time(ref, arrival_threshold_m, t0, t1);
  e.arrival_diff_s = e.arrival_s - e.ref_arrival_s;
  e.rms_rel = e.rms_m / std::fabs(e.ref_peak_m);
  return e;
}

namespace {
// `*` takes none, one, ... characters of the name, never a '.'. Recursive: names and patterns are a few
// dozen characters with one or two stars.
bool match_from(const char* p, const char* n) {
  if (*p == '\0') return *n == '\0';
  if (*p == '*') {
    for (const char* k = n;; ++k) {
      if (match_from(p + 1, k)) return true;
      if (*k == '\0' || *k == '.') return false;
    }
  }
  return *p == *n && match_from(p + 1, n + 1);
}
}  // namespace

bool wildcard_match(const std::string& pattern, const std::string& name) {
  return match_from(pattern.c_str(), name.c_str());
}

std::vector<MetricOutput> expand_metric_patterns(const std::vector<MetricOutput>& patterns,
                                                 const std::vector<std::string>& reference_names,
                                                 std::vector<size_t>* unmatched) {
  std::vector<MetricOutput> out;
  auto add = [&](const std::string& name, double scale) {
    for (const auto& m : out)
      if (m.name == name) return;
    out.push_back({name, scale});
  };
  for (size_t i = 0; i < patterns.size(); ++i) {
    const MetricOutput& p = patterns[i];
    if (p.name.find('*') == std::string::npos) {
      add(p.name, p.scale);
      continue;
    }
    bool matched = false;
    for (const auto& n : reference_names)
      if (wildcard_match(p.name, n)) {
        add(n, p.scale);
        matched = true;
      }
    if (!matched && unmatched) unmatched->push_back(i);
  }
  return out;
}

bool reference_defines(const MetricError& e) {
  return std::isfinite(e.ref.value) && std::max(std::fabs(e.ref.value), e.scale) > 0;
}

MetricError compare_metric(const MetricOutput& metric, const MetricReading& value, const MetricReading& ref) {
  MetricError e;
  e.name = metric.name;
  e.scale = metric.scale;
  e.value = value;
  e.ref = ref;
  if (std::isfinite(value.value) && std::isfinite(ref.value)) {
    e.diff = value.value - ref.value;
    if (reference_defines(e)) e.rel = std::fabs(e.diff) / std::max(std::fabs(ref.value), metric.scale);
  }
  return e;
}

std::string reading_problem(const MetricReading& m) {
  if (!m.present) return "missing";
  return std::isfinite(m.value) ? "" : "not finite";
}

std::string metric_problem(const MetricError& e) {
  const std::string ref = reading_problem(e.ref);
  if (!ref.empty()) return "reference " + ref;
  if (!reference_defines(e)) return "reference 0, scale 0";
  return reading_problem(e.value);
}

double mean_metric_error(const std::vector<MetricError>& errors) {
  double sum = 0;
  size_t n = 0;
  for (const auto& e : errors) {
    if (!reference_defines(e)) continue;  // the same for every run: left out of every mean alike
    if (!std::isfinite(e.rel)) return kNaN;
    sum += e.rel;
    ++n;
  }
  return n ? sum / double(n) : kNaN;
}

std::vector<bool> pareto_front(const std::vector<double>& cost, const std::vector<double>& error) {
  const size_t n = cost.size();
  std::vector<bool> front(n, false);
  auto ok = [&](size_t i) { return std::isfinite(cost[i]) && std::isfinite(error[i]); };
  for (size_t i = 0; i < n; ++i) {
    if (!ok(i)) continue;
    bool dominated = false;
    for (size_t j = 0; j < n && !dominated; ++j)
      dominated = j != i && ok(j) && cost[j] <= cost[i] && error[j] <= error[i] &&
                  (cost[j] < cost[i] || error[j] < error[i]);
    front[i] = !dominated;
  }
  return front;
}

}  // namespace flume::study
