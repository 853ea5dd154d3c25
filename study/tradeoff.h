// `flume study tradeoff`: one scene over a list of fidelity settings (dx, ppc, precision, K, CFL, J-bar psi,
// variant scene files), each run's cost and its error against a reference (the finest setting or a measured
// record) on gauges, load cells and run.json metrics (debris displacements, peak forces), the Pareto front of
// each error against cost, as a table (markdown, CSV) and an SVG plot.
//
// The runs are a campaign with a `list` design (campaigns/spec.h) in the campaign store: the study is
// resumable, a killed study loses no finished run, and `flume campaign status|export` and `flume report`
// read it like any other campaign.
//
// Spec (JSON):
//   {"name": "tradeoff-waseda-2d", "description": "...", "scene": "scenes/waseda/waseda_2d.json",
//    "overrides": {"solver.end_time": 4},
//    "settings": [{"label": "dx 0.02", "solver.dx": 0.02}, {"label": "3D half", "scene": "...", ...}, ...],
//    "reference": {"setting": "dx 0.02"}  |  {"records": "measured.csv"},
//    "outputs": {"gauges": ["WG1", ...], "loads": [...], "window_s": [0, 4], "arrival_threshold_m": 0.005,
//                "front_s": 1.0,
//                "metrics": ["D*.longitudinal_max_m", {"name": "D1.lateral_rest_m", "scale": 0.015}, ...]},
//    "run": {"time_limit_s": 1800, "threads": 2}}
//
// `gauges` and `loads` default to all of the scene's; `metrics` to none. A metric is a name in each run's
// run.json `metrics` object (solver/run_output.cpp, solver/debris_metrics.cpp), given as a string or as
// {"name", "scale"}; `*` matches any run of characters other than '.' and is expanded against the
// reference run's names (study/compare.h, expand_metric_patterns). `scale` (default 0, in the metric's unit)
// floors the relative difference's denominator: |value - reference| / max(|reference|, scale). At least one
// gauge, load cell or metric; metrics need a reference setting (a measured record has none).
#pragma once

namespace CLI {
class App;
}
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "campaigns/spec.h"
#include "store/db/campaign_store.h"
#include "study/compare.h"

namespace flume::study {

struct TradeoffSpec {
  std::string file;
  campaigns::CampaignSpec campaign;  // the runs: one list-design point per setting, in the spec's order
  std::vector<std::string> labels;   // one per setting
  std::optional<size_t> reference_setting;  // the setting compared against, or
  std::string reference_records;            // a measured gauge record (CSV, calibration/records.h)
  std::vector<std::string> gauges, loads;
  std::vector<std::string> scene_gauges;  // every gauge of the base scene (a record may have columns for all)
  double window_start_s = 0, window_end_s = 0;
  double arrival_threshold_m = 0.005;
  // > 0: each gauge's RMS only over [a - front_s / 4, a + front_s] around the reference's arrival a there
  // (the bore and what follows it at once), not over the whole window, whose tail (breaking, splash,
  // reflections) no resolution reproduces sample by sample. 0: the whole window.
  double front_s = 0;
  std::vector<MetricOutput> metrics;  // as the spec gives them: names or patterns with `*`
};

// Throws flume::InputError naming the file and the field (`settings.3.solver.dx`) with what is allowed.
TradeoffSpec parse_tradeoff_spec(const std::string& json_text, const std::string& file_label,
                                 const std::string& base_dir);
TradeoffSpec load_tradeoff_spec(const std::string& file);

enum ErrorMeasure { kRms = 0, kPeak = 1, kArrival = 2, kMetric = 3, kMeasureCount = 4 };
inline const char* kErrorNames[kMeasureCount] = {"rms", "peak", "arrival", "metric"};

struct LoadError {
  std::string name;
  double peak_n = 0, ref_peak_n = 0, peak_rel = 0;
};

struct SettingResult {
  std::string label;
  std::int64_t run_id = 0;  // in the store; 0: not there
  std::string changes;      // what the setting sets, "path=value" joined
  store::RunStatus status = store::RunStatus::kPending;
  std::string message;
  double wall_s = NAN, particle_steps = NAN, peak_rss_mb = NAN;
  long long steps = -1, particles = -1;
  std::vector<GaugeError> gauges;
  std::vector<LoadError> loads;
  std::vector<MetricError> metrics;  // one per TradeoffResult::metrics, for a run with a result
  // Four aggregate errors, each with its own Pareto front against wall time (index: ErrorMeasure):
  //  rms: mean over gauges of RMS(difference) / |reference peak| (the whole record, phase included);
  //  peak: mean over gauges and load cells of |peak - reference peak| / |reference peak|;
  //  arrival: mean over gauges of |arrival - reference arrival| in s (where only one of them arrived, the
  //  time from that arrival to the window's end, the least the miss can be);
  //  metric: mean over the metrics of |value - reference| / max(|reference|, scale) (mean_metric_error).
  double error[kMeasureCount] = {NAN, NAN, NAN, NAN};
  bool reference = false;
  bool pareto[kMeasureCount] = {false, false, false, false};
};

struct TradeoffResult {
  std::string reference;  // what the errors are against, in words
  std::vector<MetricOutput> metrics;  // the spec's metrics, wildcards expanded against the reference run
  // The errors the spec has outputs for (no gauges: no rms and no arrival; no metrics: no metric); the
  // others are neither stored nor plotted.
  bool measured[kMeasureCount] = {false, false, false, false};
  std::vector<SettingResult> rows;
};

// Reads every setting's run from the store, its result file and its run.json. Throws InputError when the
// reference has no result (it ended unstable, failed, or has not run), and naming `outputs.metrics.<i>` when
// a pattern with `*` matches none of the reference's metrics.
TradeoffResult evaluate_tradeoff(const TradeoffSpec& spec, const std::string& db_file);

// Each run's errors into the store as metrics (`error.rms`, `error.peak`, `error.arrival_s`, `error.metric`,
// `pareto.<error>`, `error.<gauge>.rms_m|peak_rel|arrival_diff_s`, `error.<load>.peak_rel`,
// `error.<metric>.diff|rel`), so that `flume campaign export` and the store's `results_<campaign>` view carry
// them beside the cost. What is not finite (a missing metric's difference) is left out, never stored as NaN.
void store_errors(const TradeoffResult& result, const std::string& db_file);

// tradeoff.md, tradeoff.csv and tradeoff.svg in `out_dir`.
void write_tradeoff(const TradeoffSpec& spec, const TradeoffResult& result, const std::string& out_dir);
std::string tradeoff_markdown(const TradeoffSpec& spec, const TradeoffResult& result);

// flume study tradeoff SPEC --db FILE [--out DIR] [--workers N]
void add_study_command(CLI::App& app);

}  // namespace flume::study
