// Parameter distributions of a campaign, as plain values. OpenTURNS builds the actual distributions
// (distribution.cpp); no OpenTURNS type appears in this header so the rest of flume need not include it.
#pragma once
#include <string>
#include <vector>

namespace flume::sampling {

enum class DistributionType { kUniform, kNormal, kLogNormal, kTruncatedNormal, kBeta, kChoice };

const char* to_string(DistributionType t);

// Only the fields of the chosen type are read. Bounds are checked by the spec parser, which knows the field
// paths; check_distribution() below is the single place that states what is allowed.
struct Distribution {
  DistributionType type = DistributionType::kUniform;
  double lower = 0.0, upper = 1.0;    // uniform, truncated normal, beta (support)
  double mean = 0.0, std = 1.0;       // normal, truncated normal (of the parent normal), lognormal (of the variable)
  double mu_log = 0.0, sigma_log = 1.0;  // lognormal: parameters of log(x)
  double alpha = 2.0, beta = 2.0;     // beta shape parameters
  // Choice: the values drawn (numbers, or strings such as boundary conditions) and optional weights.
  std::vector<double> numeric_choices;
  std::vector<std::string> text_choices;
  std::vector<double> weights;  // empty: equally likely

  bool is_text_choice() const { return type == DistributionType::kChoice && !text_choices.empty(); }
  size_t choice_count() const { return text_choices.empty() ? numeric_choices.size() : text_choices.size(); }
};

// Empty when the distribution is valid, else "<field>: <what is wrong and what is allowed>" with the field
// relative to the distribution object (e.g. "upper: must exceed lower (0.55 <= 0.15)").
std::string check_distribution(const Distribution& d);

// Cumulative distribution function (for choices: of the index 0..k-1), via OpenTURNS.
double cdf(const Distribution& d, double x);
// Inverse CDF at probability p in (0, 1) (for choices: the index).
double quantile(const Distribution& d, double p);

}  // namespace flume::sampling

namespace flume::sampling {
// A lognormal given by the mean and standard deviation of the variable itself (what an engineer usually
// knows), converted by OpenTURNS' LogNormalMuSigma. Requires mean > 0 and std > 0.
Distribution lognormal_from_mean_std(double mean, double std);
}  // namespace flume::sampling
