// Surrogates of one campaign metric, fitted and validated by OpenTURNS (surrogate/ot_models.h):
//   chaos    polynomial chaos, least squares with LARS selection; Sobol' indices from its coefficients
//            (OT::FunctionalChaosSobolIndices) with percentile-bootstrap intervals
//   kriging  constant trend, Matern 5/2 covariance by maximum likelihood; a prediction carries its variance
// Validation: Q2 = 1 - sum (y - y_hat)^2 / sum (y - mean y)^2 over out-of-fold predictions (k-fold by
// OT::KFoldSplitter; k = n is leave-one-out), and over runs held back from the fit (OT::MetaModelValidation).
// Exceedance curve P(Y > t): the surrogate on a Monte Carlo sample of the input law; its band from the
// bootstrap replicates, each on a sample of its own (surrogate and sampling error together).
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "surrogate/data.h"

namespace flume::surrogate {

enum class Kind { kChaos, kKriging };
const char* to_string(Kind k);
std::optional<Kind> kind_from(const std::string& s);

struct FitSettings {
  Kind kind = Kind::kChaos;
  int degree = 0;            // chaos total degree; 0: the largest whose full basis has at most n terms
  std::size_t folds = 5;     // k of the k-fold Q2; 0 or >= n: leave-one-out
  std::size_t holdout = 0;   // the last runs (design order) kept out of the fit for a held-back Q2
  std::string validation;    // or: another campaign (same parameters) whose runs are the held-back ones
  std::string given;         // fit only runs where this metric exists (TrainingData::given)
  std::size_t bootstrap = 200;  // chaos replicates for the intervals; 0: none
  double confidence = 0.95;
  std::size_t mc_size = 20000;  // input sample of the exceedance curve (per replicate: mc_size / 10)
  std::vector<double> thresholds;  // empty: 25 between the 2 % and 99.5 % quantiles of the output
  std::uint64_t seed = 1;
};

struct Estimate {
  double value = 0, lo = 0, hi = 0;
};

struct ExceedanceCurve {
  std::vector<double> thresholds, p, lo, hi;  // lo/hi: NaN without replicates
  std::size_t mc_size = 0, replicates = 0;
  std::size_t band_points = 0;  // input points each replicate (chaos) or realisation (kriging) is evaluated on
};

// The classifier of where a metric (or the fit's condition) exists, surrogate/classifier.h.
struct ClassifierQuality {
  std::size_t inside = 0, outside = 0;  // training runs of each class
  double accuracy_cv = 0;  // the share of training runs classified right, leave-one-out (20-fold over 200)
  std::size_t holdout_inside = 0, holdout_outside = 0;
  double accuracy_holdout = 0;  // on the held-back runs; NaN without any
  double p_inside = 0;          // P(inside) under the input law (Monte Carlo on the classifier)
};

struct FitResult {
  Kind kind = Kind::kChaos;
  std::vector<std::int64_t> train_runs, holdout_runs;
  int degree = 0;          // chaos
  std::size_t terms = 0;   // chaos: terms kept by LARS
  std::size_t folds = 0;
  double q2_cv = 0;
  std::vector<double> cv_observed, cv_predicted;  // out-of-fold, training runs in design order
  double q2_holdout = 0;  // NaN without held-back runs
  std::vector<double> holdout_observed, holdout_predicted;
  std::vector<Estimate> first, total;  // chaos: Sobol' indices per input
  std::size_t sobol_replicates = 0;
  double mean = 0, std = 0;  // of the output under the input law, from the surrogate
  ExceedanceCurve exceedance;  // with a condition or runs without the metric: given that it exists
  std::optional<ClassifierQuality> classifier;  // when some training runs are outside
  std::string model;  // the OpenTURNS result, as XML
};

// Throws flume::InputError for settings the data cannot support (holdout leaving too few runs).
FitResult fit_surrogate(const TrainingData& data, const FitSettings& settings);

// The store's JSON texts of a fit (nlohmann-json, read back by the report and `surrogate sobol`).
std::string settings_json(const FitSettings& s);
std::string quality_json(const FitResult& r, const TrainingData& data, const FitSettings& s);
std::string runs_json(const FitResult& r);
// What decides a fit: settings, runs and their values. An unchanged hash means the stored fit is current.
std::string fit_hash(const TrainingData& data, const FitSettings& s);

// A stored surrogate, loaded to evaluate it.
class Surrogate {
 public:
  Surrogate(Kind kind, const std::string& model_xml);
  ~Surrogate();
  Surrogate(Surrogate&&) noexcept;
  Kind kind() const { return kind_; }
  std::size_t dimension() const;
  std::vector<double> predict(const std::vector<std::vector<double>>& points) const;
  // Kriging: the conditional variance at each point; chaos: empty.
  std::vector<double> variance(const std::vector<std::vector<double>>& points) const;

 private:
  struct Impl;
  Kind kind_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace flume::surrogate
