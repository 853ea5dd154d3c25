// The misfit between simulated and target gauge records over the objective window:
//   J = RMS + w_peak * peak error + w_arrival * arrival error                      (all in m)
//   RMS           = sqrt( sum_g w_g sum_i (eta_sim,g(t_i - s) - eta_g(t_i))^2 / sum_g w_g n_g ), t_i in
//   window peak error    = sqrt( sum_g w_g (max_i eta_sim,g(t_i - s) - max_i eta_g(t_i))^2 / sum_g w_g )
//   arrival error = the same over arrival times (first up-crossing of the threshold, interpolated)
// with s the time shift (positive delays the simulation; 0 when it is not a parameter) and the simulated
// record interpolated linearly at the target's sample times.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "calibration/records.h"
#include "calibration/spec.h"

namespace flume::calibration {

struct GaugeTerms {
  double rms_m = 0, peak_error_m = 0, arrival_error_s = 0;
  size_t samples = 0;
};

struct ObjectiveTerms {
  double value = 0;  // J
  double rms_m = 0, peak_error_m = 0, arrival_error_s = 0;
  std::map<std::string, GaugeTerms> gauges;
  bool failed = false;  // the run failed: `value` is the penalty
  std::string failure;
};

// First time in [t0, t1] at which the record reaches `threshold`, interpolated between samples.
std::optional<double> arrival_time(const std::vector<double>& time, const std::vector<double>& value,
                                   double threshold, double t0, double t1);

// The objective of one stage of a window continuation: `spec` over [window_start_s, end_s].
ObjectiveSpec stage_objective(const ObjectiveSpec& spec, double end_s);

class Objective {
 public:
  // Throws InputError when the arrival term is weighted and a target never arrives in the window.
  Objective(const ObjectiveSpec& spec, const std::vector<TargetRecord>& targets,
            const std::string& spec_file);

  ObjectiveTerms evaluate(const std::map<std::string, SimRecord>& sim, double shift_s) const;
  // What a failed run scores: twice the objective of a simulation that stays at still water, so any run
  // that moves water the right way beats it, deterministically (a resumed calibration replays it exactly).
  ObjectiveTerms failure(const std::string& why) const;
  // sqrt(w_g) (sim - target) at every window sample, gauges in target order (for the Gauss-Newton analysis).
  std::vector<double> residuals(const std::map<std::string, SimRecord>& sim, double shift_s) const;

  struct Window {
    std::string gauge;
    double weight;
    std::vector<double> time, target;  // the target's samples inside the window
    double peak_m;
    std::optional<double> arrival_s;
  };
  const std::vector<Window>& windows() const { return windows_; }
  double window_start_s() const { return spec_.window_start_s; }
  double window_end_s() const { return spec_.window_end_s; }

 private:
  ObjectiveSpec spec_;
  std::vector<Window> windows_;
  double failure_value_ = 0;
};

}  // namespace flume::calibration
