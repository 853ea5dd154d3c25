// A calibration spec: JSON parsed and validated once (spec.cpp) into these plain structs, target records
// included, before anything touches the store or starts a run. Every error is a flume::InputError naming the
// file, the field path (or CSV line and column) and what is allowed.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "calibration/records.h"

namespace flume::calibration {

enum class Scale { kLinear, kLog };

// A free parameter. The optimizer sees u in [0, 1]: value = lower + u (upper - lower), or geometric for kLog.
struct FreeParameter {
  std::string path;  // scene path or model input; kTimeShiftPath for the objective's time shift
  double lower = 0, upper = 1, start = 0;
  Scale scale = Scale::kLinear;
  bool needs_run = true;  // false for the time shift: it moves the simulated record, it does not rerun it
  double to_unit(double value) const;
  double from_unit(double u) const;
};
inline constexpr const char* kTimeShiftPath = "objective.time_shift_s";

// One CSV file of target records: which of its columns are which gauges.
struct TargetFile {
  std::string file;                                                // as resolved
  std::vector<std::pair<std::string, std::string>> gauge_columns;  // gauge -> column name; empty: all columns
  double weight = 1.0;
};

struct ObjectiveSpec {
  double window_start_s = 0, window_end_s = 0;
  // Window continuation: the optimizer fits [window_start_s, stage_end_s[k]] for each k in turn, each from
  // the one before's optimum, then the whole window. A record whose late part answers the parameters
  // nonlinearly (reflections, trailing waves) has a misfit with a local minimum in every dent; its early
  // part decides the basin (docs/calibration.md, "Window continuation").
  std::vector<double> stage_end_s;
  double peak_weight = 0.0;             // on the peak elevation error (m per m)
  double arrival_weight_m_per_s = 0.0;  // on the arrival time error
  double arrival_threshold_m = 0.005;   // arrival: first exceedance, as the run metrics define it
};

// How NLopt is driven. Budgets and time are not part of the calibration's identity: a calibration stopped by
// them continues, with the same trajectory, when it is run again with larger ones.
struct AlgorithmSpec {
  std::string name = "BOBYQA";
  std::string local;            // MLSL's local optimizer
  std::string polish;           // optional local optimizer run from a global algorithm's best point
  int max_evaluations = 100;    // per start
  int polish_evaluations = 50;  // per start
  double max_time_s = 0;        // whole invocation; 0: none
  double xtol_abs = 1e-4;       // in unit coordinates
  double ftol_abs = 0;          // m; 0: off
  double initial_step = 0.1;    // local algorithms' first step, in unit coordinates
  double stage_step = 0.01;     // the first step of each fit after the first stage: it refines, not searches
  int population = 0;           // CRS2_LM / ISRES population; 0: NLopt's default
  std::uint64_t seed = 1;
};

struct ProfileSpec {
  int points = 5;      // on each side of the optimum; 0: no profiles
  double span = 0.15;  // in unit coordinates, on each side
};

struct RunSettings {
  double time_limit_s = 3600.0;
  int threads = 1;
  std::string output_dir;  // empty: "<db>.runs/<name>"
};

struct CalibrationSpec {
  std::string file, name, description;
  std::string scene;                                           // absolute path; empty for a model
  std::string model;                                           // "gauge" (test stand-in); empty for a scene
  std::vector<std::pair<std::string, std::string>> overrides;  // path -> JSON text
  std::vector<TargetFile> target_files;
  std::vector<TargetRecord> targets;      // read and checked
  std::vector<FreeParameter> parameters;  // those that need a run first, then the time shift if any
  ObjectiveSpec objective;
  AlgorithmSpec algorithm;
  std::vector<std::vector<double>> starts;  // physical values in parameter order; starts[0] from `start`
  ProfileSpec profile;
  RunSettings run;
  std::vector<std::string> gauges;  // the scene's (or model's) gauges
  double record_end_s = 0;          // the simulated record's end (solver.end_time)
  std::string canonical;  // identity: the spec without description/run/budgets/profile, with content hashes
  std::string hash;       // of `canonical`; a changed spec under a stored name is refused

  size_t run_parameter_count() const;
};

CalibrationSpec load_calibration_spec(const std::string& file);
CalibrationSpec parse_calibration_spec(const std::string& json_text, const std::string& file_label,
                                       const std::string& base_dir);

// The algorithm names `algorithm.name` accepts, and whether one is local.
std::vector<std::string> algorithm_names();
bool is_local_algorithm(const std::string& name);

}  // namespace flume::calibration
