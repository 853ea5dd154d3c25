#include "common/gauge_summary.h"

#include <cmath>

namespace flume {

GaugeSummary summarize_gauge(const std::vector<double>& time, const std::vector<double>& value, double threshold) {
  GaugeSummary s;
  bool have_first = false;
  for (std::size_t i = 0; i < value.size() && i < time.size(); ++i) {
    const double e = value[i];
    if (!std::isfinite(e)) continue;
    if (!have_first) {
      s.first = e;
      have_first = true;
    }
    if (!s.has_peak || e > s.peak) {
      s.peak = e;
      s.peak_time = time[i];
      s.has_peak = true;
    }
    if (!s.arrived && e >= s.first + threshold) {
      s.arrived = true;
      s.arrival_time = time[i];
    }
  }
  return s;
}

PressureSummary summarize_pressure(const std::vector<double>& time, const std::vector<double>& value) {
  PressureSummary s;
  bool any = false;
  for (std::size_t i = 0; i < time.size() && i < value.size(); ++i) {
    if (!std::isfinite(value[i]) || !std::isfinite(time[i])) continue;
    if (!any || value[i] > s.peak) {
      s.peak = value[i];
      s.peak_time = time[i];
      any = true;
    }
    if (i > 0 && std::isfinite(time[i - 1])) s.impulse += value[i] * (time[i] - time[i - 1]);
  }
  return s;
}

}  // namespace flume
