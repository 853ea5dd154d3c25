// Calibration with uncertainty: the posterior of a calibration's free parameters given the gauge records
// under a noise model, sampled by OpenTURNS' RandomWalkMetropolisHastings on a surrogate rather than on
// solver runs: of the gauge series (series_posterior.h, the default) or, here, of the misfit.
//   likelihood  independent Gaussian residuals of standard deviation sigma (the noise model):
//               log L(theta) = -SSR(theta) / (2 sigma^2) + const,  SSR = sum of squared residuals over the
//               n samples of every target record (n RMS^2, RMS the calibration's stored term)
//   prior       uniform on the calibration's bounds
//   surrogate   kriging of SSR with a quadratic trend (a least-squares misfit is a quadratic bowl near its
//               minimum) over the evaluations near the best one (every optimizer and profile point whose SSR
//               is within 50 * 2 sigma^2 of the least: a log-likelihood drop of 50; at least
//               posterior_min_evaluations of the lowest), in
//               unit coordinates of the bounds. Far from the minimum the misfit spans orders of magnitude a
//               stationary surrogate cannot follow: fitted there too, it invents minima the chain falls into.
// Gauge residuals are correlated in time, so with the full sample count the intervals are optimistic; the
// noise model's sigma (or an effective n) is the user's statement of how much the records constrain.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace flume::surrogate {

// A calibration's free parameters (a time shift last) and its stored spec.
struct CalibrationBox {
  std::vector<std::string> names;
  std::vector<double> lower, upper;
  std::string spec_json;  // the calibration's stored spec (its scene or model and overrides)
};

struct MisfitData : CalibrationBox {
  std::vector<std::vector<double>> points;  // parameter values of each evaluation
  std::vector<double> ssr;                  // its sum of squared residuals, m^2
  double n_residuals = 0;
};

struct PosteriorSettings {
  double noise_m = 0.005;
  std::size_t samples = 20000, burn_in = 2000;
  double confidence = 0.95;
  std::uint64_t seed = 1;
  std::size_t draws = 0;  // posterior points kept for the predictive runs, evenly spaced along the chain
  // The series emulator's own error variance in the likelihood (series_posterior.h). Off only to show, in
  // the tests, what leaving it out does.
  bool emulator_error = true;
  // The series emulator's neighbourhood: the evaluations whose records lie within this many noises of the best's.
  double neighbourhood = 1.0;
};

struct PosteriorParameter {
  std::string name;
  double best = 0;  // the evaluation with the least misfit
  double mean = 0, median = 0, lo = 0, hi = 0;
  bool cut = false;  // the interval reaches the edge of where the surrogate has evaluations: evaluate wider
};

struct Posterior {
  std::vector<PosteriorParameter> parameters;
  std::size_t evaluations = 0;
  double acceptance = 0;
  double q2 = 0;  // leave-one-out Q2 of the surrogate (misfit, or the series) over its (local) evaluations
  std::size_t local = 0;       // evaluations the surrogate is fitted to
  std::size_t components = 0;  // series emulator: principal components kept
  double emulator_rms = 0;     // series emulator: RMS of its leave-one-out error over the series, m
  double best_rms = 0;  // the least misfit's RMS, m: well above the noise means model error or no optimum
  std::vector<std::vector<double>> draws;  // in the parameters' units, `names` order
};

// The largest best-fit RMS, as a multiple of the noise sigma, that noise alone gives over n independent
// residuals at `level` (n RMS^2 / sigma^2 is chi-square with n degrees of freedom): beyond it the residual is
// not the noise the likelihood assumes (model error, or an optimizer stopped in a local minimum).
double noise_alone_rms_ratio(double n_residuals, double level);

// The evaluations a misfit surrogate of p parameters needs: a quadratic's (p + 1)(p + 2) / 2 coefficients and
// p + 1 more for the kriging of what it leaves.
inline std::size_t posterior_min_evaluations(std::size_t p) { return (p + 1) * (p + 2) / 2 + p + 1; }

Posterior misfit_posterior(const MisfitData& data, const PosteriorSettings& settings);

// The phase of the evaluations the posterior's refinement adds (posterior_refine.h), their start its round.
inline constexpr const char* kRefinePhase = "refine";
inline constexpr int kAllRounds = 1 << 30;

// The stored evaluations of calibration `name` (flume calibrate), with the refinement's of rounds before
// `rounds_before`: failed evaluations are left out. Throws flume::InputError naming the file for an unknown
// calibration or too few evaluations.
MisfitData load_calibration_misfit(const std::string& db_file, const std::string& name,
                                   int rounds_before = kAllRounds);

// The predictive runs: a campaign spec (list design, docs/campaign-spec.md) of the optimum (the best
// evaluation, labelled "optimum") and the posterior draws ("draw-001", ...) on the
// calibration's scene and overrides, `end_time_s` (> 0) replacing its simulated time, so that `flume campaign
// run` gives the records whose spread is the predictive band (`flume gauges --band`). A time shift of the
// comparison is not a scene value and is left out. Throws flume::InputError for a calibration of a stand-in
// model or a scene file no longer there.
std::string predictive_spec(const CalibrationBox& data, const Posterior& posterior,
                            const std::string& calibration, double end_time_s);

}  // namespace flume::surrogate
