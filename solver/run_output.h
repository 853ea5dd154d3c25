// What a finished (or stopped) run leaves behind: result.h5 with the recorded series, and run.json with
// status, message, metrics and cost. Both are written to a temporary name and renamed when complete.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "common/gauge_summary.h"
#include "solver/simulation.h"

namespace flume {

// Per-run scalar metrics from the record: for every gauge its peak elevation, the peak's time and the
// arrival time (first exceedance of `arrival_threshold_m`); for every load cell the peak force magnitude,
// peak streamwise force and streamwise impulse; for every pressure probe its peak pressure, the peak's time
// and the pressure impulse (summarize_pressure, common/gauge_summary.h). No metric is ever NaN: a gauge the wave never reaches has
// `<gauge>.arrived = 0` and no arrival time (summarize_gauge, common/gauge_summary.h).
std::map<std::string, double> compute_metrics(const Scene& scene, const Record& record,
                                              double arrival_threshold_m = 0.005);

std::string status_name(RunStatus s);

// Writes DIR/run.json atomically.
void write_run_json(const std::string& path, RunStatus status, const std::string& message,
                    const std::map<std::string, double>& metrics, const Cost& cost, const Scene& scene);

}  // namespace flume
