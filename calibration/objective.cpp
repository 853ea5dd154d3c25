#include "calibration/objective.h"

#include <algorithm>
#include <cmath>

#include "common/errors.h"
#include "common/input/fields.h"

namespace flume::calibration {

std::optional<double> arrival_time(const std::vector<double>& time, const std::vector<double>& value,
                                   double threshold, double t0, double t1) {
  for (size_t k = 0; k < time.size(); ++k) {
    if (time[k] < t0) continue;
    if (time[k] > t1) break;
    if (value[k] >= threshold) {
      if (k == 0 || time[k - 1] < t0 || value[k - 1] >= threshold) return time[k];
      const double w = (threshold - value[k - 1]) / (value[k] - value[k - 1]);
      return std::max(t0, time[k - 1] + w * (time[k] - time[k - 1]));
    }
  }
  return std::nullopt;
}

ObjectiveSpec stage_objective(const ObjectiveSpec& spec, double end_s) {
  ObjectiveSpec stage = spec;
  stage.window_end_s = end_s;
  stage.stage_end_s.clear();
  return stage;
}

Objective::Objective(const ObjectiveSpec& spec, const std::vector<TargetRecord>& targets,
                     const std::string& spec_file)
    : spec_(spec) {
  for (const auto& r : targets) {
    Window w;
    w.gauge = r.gauge;
    w.weight = r.weight;
    for (size_t k = 0; k < r.time.size(); ++k)
      if (r.time[k] >= spec.window_start_s && r.time[k] <= spec.window_end_s) {
        w.time.push_back(r.time[k]);
        w.target.push_back(r.elevation[k]);
      }
    if (w.time.empty())
      throw InputError(spec_file, "objective.window",
                       "the target of " + r.gauge + " (" + r.file + ") has no sample in [" +
                           input::number_text(spec.window_start_s) + ", " +
                           input::number_text(spec.window_end_s) + "] s");
    w.peak_m = *std::max_element(w.target.begin(), w.target.end());
    w.arrival_s =
        arrival_time(w.time, w.target, spec.arrival_threshold_m, spec.window_start_s, spec.window_end_s);
    if (spec.arrival_weight_m_per_s > 0 && !w.arrival_s)
      throw InputError(
          spec_file, "objective.arrival_weight_m_per_s",
          "the target of " + r.gauge + " (" + r.file +
              ") never reaches arrival_threshold_m in the "
              "window, so it has no arrival time to fit; lower the threshold or set the weight to 0");
    windows_.push_back(std::move(w));
  }
  std::map<std::string, SimRecord> still;
  for (const auto& w : windows_)
    still[w.gauge] = SimRecord{{spec.window_start_s, spec.window_end_s}, {0.0, 0.0}};
  failure_value_ = 2.0 * evaluate(still, 0.0).value;
}

ObjectiveTerms Objective::evaluate(const std::map<std::string, SimRecord>& sim, double shift_s) const {
  ObjectiveTerms out;
  double sum2 = 0, n = 0, peak2 = 0, arrival2 = 0, wsum = 0;
  for (const auto& w : windows_) {
    auto it = sim.find(w.gauge);
    if (it == sim.end() || it->second.time.empty()) return failure("no simulated record of " + w.gauge);
    const SimRecord& s = it->second;
    GaugeTerms g;
    double g2 = 0, sim_peak = -INFINITY;
    std::vector<double> shifted(w.time.size());
    for (size_t k = 0; k < w.time.size(); ++k) {
      shifted[k] = interpolate(s.time, s.elevation, w.time[k] - shift_s);
      if (!std::isfinite(shifted[k])) return failure("the simulated record of " + w.gauge + " is not finite");
      const double r = shifted[k] - w.target[k];
      g2 += r * r;
      sim_peak = std::max(sim_peak, shifted[k]);
    }
    g.samples = w.time.size();
    g.rms_m = std::sqrt(g2 / static_cast<double>(g.samples));
    g.peak_error_m = std::fabs(sim_peak - w.peak_m);
    if (w.arrival_s) {
      // A simulated wave that never arrives is taken to arrive at the window's end.
      const auto a =
          arrival_time(w.time, shifted, spec_.arrival_threshold_m, spec_.window_start_s, spec_.window_end_s);
      g.arrival_error_s = std::fabs(a.value_or(spec_.window_end_s) - *w.arrival_s);
    } else {
      g.arrival_error_s = 0;  // nothing to compare (its weight is then 0, see the constructor)
    }
    sum2 += w.weight * g2;
    n += w.weight * static_cast<double>(g.samples);
    peak2 += w.weight * g.peak_error_m * g.peak_error_m;
    arrival2 += w.weight * g.arrival_error_s * g.arrival_error_s;
    wsum += w.weight;
    out.gauges[w.gauge] = g;
  }
  out.rms_m = std::sqrt(sum2 / n);
  out.peak_error_m = std::sqrt(peak2 / wsum);
  out.arrival_error_s = std::sqrt(arrival2 / wsum);
  out.value =
      out.rms_m + spec_.peak_weight * out.peak_error_m + spec_.arrival_weight_m_per_s * out.arrival_error_s;
  return out;
}

ObjectiveTerms Objective::failure(const std::string& why) const {
  ObjectiveTerms out;
  out.failed = true;
  out.failure = why;
  out.value = failure_value_;
  out.rms_m = out.peak_error_m = out.arrival_error_s = std::nan("");
  return out;
}

std::vector<double> Objective::residuals(const std::map<std::string, SimRecord>& sim, double shift_s) const {
  std::vector<double> r;
  for (const auto& w : windows_) {
    const SimRecord& s = sim.at(w.gauge);
    const double sw = std::sqrt(w.weight);
    for (size_t k = 0; k < w.time.size(); ++k)
      r.push_back(sw * (interpolate(s.time, s.elevation, w.time[k] - shift_s) - w.target[k]));
  }
  return r;
}

}  // namespace flume::calibration
