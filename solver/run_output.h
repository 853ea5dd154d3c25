// What a finished (or stopped) run leaves behind: result.h5 with the recorded series, and run.json with
// status, message, metrics and cost. Both are written to a temporary name and renamed when complete.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "solver/simulation.h"

namespace flume {

// Per-run scalar metrics from the record: for every gauge its peak elevation, the peak's time and the
// arrival time (first exceedance of `arrival_threshold_m`); for every load cell the peak force magnitude,
// peak streamwise force and streamwise impulse. No metric is ever NaN: a gauge the wave never reaches has
// `<gauge>.arrived = 0` and no arrival time.
// Peak and arrival of one gauge record (non-finite samples are skipped). The arrival is the first time the
// record rises `threshold` above its first finite reading (0 in still water; the ground's height where the
// gauge starts dry, as on an apron); arrived is false when it never does. compute_metrics and `flume gauges`
// both use it.
struct GaugeSummary {
  bool has_peak = false, arrived = false;
  double peak = 0, peak_time = 0, first = 0, arrival_time = 0;
};
GaugeSummary summarize_gauge(const std::vector<double>& time, const std::vector<double>& value, double threshold);

std::map<std::string, double> compute_metrics(const Scene& scene, const Record& record,
                                              double arrival_threshold_m = 0.005);

std::string status_name(RunStatus s);

// Writes DIR/run.json atomically.
void write_run_json(const std::string& path, RunStatus status, const std::string& message,
                    const std::map<std::string, double>& metrics, const Cost& cost, const Scene& scene);

}  // namespace flume
