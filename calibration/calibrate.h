// A calibration: NLopt from each start over the free parameters scaled to [0, 1], every objective
// evaluation a run in the store (see evaluator.h); then the objective's profile along each parameter
// through the optimum and a Gauss-Newton look at identifiability. Resuming replays the same deterministic
// trajectories (NLopt's random algorithms are seeded per start) and finds each point's run in the store.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "calibration/objective.h"
#include "calibration/records.h"
#include "calibration/spec.h"

namespace flume::calibration {

struct CalibrateOptions {
  std::string db_file;
  std::string out_dir;
  int workers = 1;  // runs at once: concurrent starts, and profile points
};

struct StartResult {
  int index = 0;
  std::vector<double> from, best;  // physical values, spec parameter order
  std::vector<double> best_u,
      first_u;  // unit coordinates of the best and the first point evaluated (exact:
                // converting back from physical values may miss the stored run by an ulp)
  double value = 0;
  ObjectiveTerms terms;
  int stage_evaluations = 0;  // the window continuation's stages before the whole window (repeats included)
  int evaluations = 0;        // the optimizer's over the whole window (repeats included)
  int polish_evaluations = 0;
  std::string stop;           // why NLopt stopped (its result), or "time budget", "stopped"
  bool same_optimum = false;  // within 2 % of each parameter's range of the best start's optimum
};

struct Profile {
  std::string path;
  std::vector<double> values, objective;  // failed runs: the penalty
  double rise_low = 0, rise_high = 0;     // (J(end) - J*) / J* at each end of the profile
};

// Gauss-Newton at the optimum (Seber & Wild 1989, sec. 2.1): the residual Jacobian J from the profiles'
// nearest points (central differences), covariance s^2 (J^T J)^-1 with s^2 = SSR / (n - p). It treats the
// residuals as independent, which a gauge record's are not, so standard errors are optimistic; correlations
// near +-1 and a large condition number are the evidence that the records cannot separate parameters.
struct Identifiability {
  bool available = false;
  std::string note;
  std::vector<double> std_error;  // physical units
  std::vector<std::vector<double>> correlation;
  std::vector<double> eigenvalues;  // of J^T J in unit coordinates, ascending
  double condition_number = 0;
  size_t samples = 0;
};

struct CalibrationResult {
  std::string status;  // "finished", "time budget", "stopped"
  std::vector<StartResult> starts;
  int best_start = 0;
  std::vector<double> best, best_u;
  ObjectiveTerms best_terms;
  std::int64_t best_run = 0;
  std::string best_run_dir;
  std::map<std::string, SimRecord> best_records, start_records;  // fitted, and start 0's first evaluation
  std::vector<Profile> profiles;
  Identifiability identifiability;
  int optimizer_evaluations = 0, profile_evaluations = 0;
  std::int64_t runs_total = 0, runs_executed = 0, runs_reused = 0;
  double run_wall_s_mean = 0, run_wall_s_total = 0, wall_s = 0;
};

// Runs (or resumes) the calibration and writes OUT/calibration.json and its SVGs. Returns the exit code:
// 0 (finished, or stopped by the time budget: run again to continue), 128 + signal when stopped.
// The store's phase of a window continuation's stage k (0-based): "stage-1", "stage-2", ...
std::string stage_phase(size_t k);

int run_calibration(const CalibrationSpec& spec, const CalibrateOptions& options, CalibrationResult& result);

// Runs `points` (physical values, spec parameter order) as evaluations of the calibration already in the
// store, recorded as (phase, round, index), after removing that phase's evaluations of this round and later:
// the posterior's refinement (flume surrogate posterior --refine). A point already run is read back; the same
// call again records the same evaluations. Returns 0, or 128 + signal when stopped.
int evaluate_points(const CalibrationSpec& spec, const std::string& db_file, const std::string& phase,
                    int round, const std::vector<std::vector<double>>& points, int workers);

}  // namespace flume::calibration
