// Distributions come from OpenTURNS; this file only maps the plain structs onto its classes.
#include "sampling/distribution.h"

#include <cmath>
#include <sstream>

#include "sampling/ot_bridge.h"

namespace flume::sampling {
namespace {

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

bool finite(double v) { return std::isfinite(v); }

}  // namespace

const char* to_string(DistributionType t) {
  switch (t) {
    case DistributionType::kUniform: return "uniform";
    case DistributionType::kNormal: return "normal";
    case DistributionType::kLogNormal: return "lognormal";
    case DistributionType::kTruncatedNormal: return "truncated_normal";
    case DistributionType::kBeta: return "beta";
    case DistributionType::kChoice: return "choice";
  }
  return "?";
}

std::string check_distribution(const Distribution& d) {
  auto bounds = [&]() -> std::string {
    if (!finite(d.lower)) return "lower: must be a finite number";
    if (!finite(d.upper)) return "upper: must be a finite number";
    if (!(d.upper > d.lower)) return "upper: must exceed lower (got lower " + num(d.lower) + ", upper " + num(d.upper) + ")";
    return "";
  };
  switch (d.type) {
    case DistributionType::kUniform: return bounds();
    case DistributionType::kNormal:
      if (!finite(d.mean)) return "mean: must be a finite number";
      if (!(d.std > 0) || !finite(d.std)) return "std: must be in (0, inf) (got " + num(d.std) + ")";
      return "";
    case DistributionType::kLogNormal:
      if (!finite(d.mu_log)) return "mu_log: must be a finite number";
      if (!(d.sigma_log > 0) || !finite(d.sigma_log))
        return "sigma_log: must be in (0, inf) (got " + num(d.sigma_log) + ")";
      return "";
    case DistributionType::kTruncatedNormal: {
      if (!finite(d.mean)) return "mean: must be a finite number";
      if (!(d.std > 0) || !finite(d.std)) return "std: must be in (0, inf) (got " + num(d.std) + ")";
      std::string b = bounds();
      if (!b.empty()) return b;
      // Far in the tail the truncated mass underflows and the quantile is meaningless.
      const double za = (d.lower - d.mean) / d.std, zb = (d.upper - d.mean) / d.std;
      if (za > 30 || zb < -30) return "lower: the interval [lower, upper] lies more than 30 std from the mean";
      return "";
    }
    case DistributionType::kBeta: {
      if (!(d.alpha > 0) || !finite(d.alpha)) return "alpha: must be in (0, inf) (got " + num(d.alpha) + ")";
      if (!(d.beta > 0) || !finite(d.beta)) return "beta: must be in (0, inf) (got " + num(d.beta) + ")";
      return bounds();
    }
    case DistributionType::kChoice: {
      if (!d.numeric_choices.empty() && !d.text_choices.empty())
        return "values: must be all numbers or all strings";
      const size_t k = d.choice_count();
      if (k < 2) return "values: must list at least 2 values (a fixed value belongs in overrides)";
      for (size_t i = 0; i < d.numeric_choices.size(); ++i)
        if (!finite(d.numeric_choices[i])) return "values." + std::to_string(i) + ": must be a finite number";
      if (!d.weights.empty()) {
        if (d.weights.size() != k)
          return "weights: must have one entry per value (" + std::to_string(k) + "), got " +
                 std::to_string(d.weights.size());
        double sum = 0;
        for (size_t i = 0; i < k; ++i) {
          if (!(d.weights[i] >= 0) || !finite(d.weights[i]))
            return "weights." + std::to_string(i) + ": must be in [0, inf)";
          sum += d.weights[i];
        }
        if (!(sum > 0)) return "weights: must not all be zero";
      }
      return "";
    }
  }
  return "type: unknown distribution";
}

namespace detail {

OT::Distribution make_ot_distribution(const Distribution& d) {
  switch (d.type) {
    case DistributionType::kUniform: return OT::Uniform(d.lower, d.upper);
    case DistributionType::kNormal: return OT::Normal(d.mean, d.std);
    case DistributionType::kLogNormal: return OT::LogNormal(d.mu_log, d.sigma_log);
    case DistributionType::kTruncatedNormal: return OT::TruncatedNormal(d.mean, d.std, d.lower, d.upper);
    case DistributionType::kBeta: return OT::Beta(d.alpha, d.beta, d.lower, d.upper);
    case DistributionType::kChoice: {
      // The support is the index of the value, so string and number choices are sampled alike.
      const size_t k = d.choice_count();
      OT::Sample support(k, 1);
      for (size_t i = 0; i < k; ++i) support(i, 0) = static_cast<double>(i);
      OT::Point weights(k, 1.0);
      for (size_t i = 0; i < d.weights.size() && i < k; ++i) weights[i] = d.weights[i];
      return OT::UserDefined(support, weights);
    }
  }
  throw std::invalid_argument("unknown distribution type");
}

}  // namespace detail

double cdf(const Distribution& d, double x) { return detail::make_ot_distribution(d).computeCDF(x); }

double quantile(const Distribution& d, double p) {
  return detail::make_ot_distribution(d).computeQuantile(p)[0];
}

}  // namespace flume::sampling

namespace flume::sampling {
Distribution lognormal_from_mean_std(double mean, double std) {
  const OT::Point p = OT::LogNormalMuSigma(mean, std, 0.0).evaluate();  // (muLog, sigmaLog, gamma)
  Distribution d;
  d.type = DistributionType::kLogNormal;
  d.mu_log = p[0];
  d.sigma_log = p[1];
  return d;
}
}  // namespace flume::sampling
