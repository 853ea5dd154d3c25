// `flume model gauge`: a TEST STAND-IN for the Waseda scene, for the calibration tests (see models.h).
// It writes what `flume run` on waseda_2d writes for its gauges (result.h5 /gauges/WG1..WG4/{time, elevation}
// at 100 Hz; peak/arrival metrics), from a reservoir draining through the gate under the hold f(t) and a
// linear long wave to the gauges. Its inputs are the scene's paths, so one calibration spec serves both:
//   reservoir.forcing.model none|exponential|table, reservoir.forcing.t99_s, reservoir.forcing.table
//   ([[time_s, hold], ...]) and its elements reservoir.forcing.table.<i>.<0|1>, reservoir.gate_height_m,
//   reservoir.fill_level_m, basin.still_water_m, solver.end_time, and two test hooks: sleep_s (wait first)
//   and undulation_m (trailing waves whose period follows the front's height: a misfit with local minima).
// It is not a model of the flume: no reflections, no apron, no nonlinearity.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace flume::campaigns {

std::vector<std::string> gauge_model_inputs();
// "" when the inputs (applied in order, as `--set` is) are acceptable, else "<name>: <problem>".
std::string check_gauge_inputs(const std::vector<std::pair<std::string, std::string>>& inputs);
// The gauges it records, and the record's end time (s) for these inputs (checked ones).
std::vector<std::string> gauge_model_gauges();
double gauge_model_end_time(const std::vector<std::pair<std::string, std::string>>& inputs);
// Runs the model on checked inputs: writes OUT_DIR/result.h5, fills the metrics and the steps taken.
void run_gauge_model(const std::vector<std::pair<std::string, std::string>>& inputs,
                     const std::string& out_dir, std::map<std::string, double>& metrics, std::int64_t& steps);

}  // namespace flume::campaigns
