#include "surrogate/multilevel.h"

#include <cmath>
#include <map>
#include <openturns/OT.hxx>
#include <stdexcept>

#include "common/errors.h"
#include "store/db/campaign_store.h"
#include "surrogate/data.h"
#include "surrogate/ot_models.h"

namespace flume::surrogate {

TwoLevelEstimate two_level_estimate(const TwoLevelSamples& s, double confidence) {
  if (s.low_only.size() < 2 || s.pair_low.size() < 2 || s.pair_low.size() != s.pair_high.size())
    throw std::invalid_argument("two-level estimate: needs at least 2 low-only runs and 2 pairs");
  if (!(s.cost_low_s > 0) || !(s.cost_high_s > 0))
    throw std::invalid_argument("two-level estimate: the costs per run must be positive");
  std::vector<double> diff(s.pair_low.size());
  for (std::size_t i = 0; i < diff.size(); ++i) diff[i] = s.pair_high[i] - s.pair_low[i];
  const OT::Sample y0 = detail::to_column(s.low_only), y1 = detail::to_column(diff),
                   yh = detail::to_column(s.pair_high);
  TwoLevelEstimate e;
  e.n0 = s.low_only.size();
  e.n1 = diff.size();
  e.v0 = y0.computeVariance()[0];
  e.v1 = y1.computeVariance()[0];
  e.v_high = yh.computeVariance()[0];
  e.mean = y0.computeMean()[0] + y1.computeMean()[0];
  e.variance = e.v0 / e.n0 + e.v1 / e.n1;
  const double z = OT::DistFunc::qNormal(0.5 + confidence / 2);
  e.lo = e.mean - z * std::sqrt(e.variance);
  e.hi = e.mean + z * std::sqrt(e.variance);
  e.cost_s = e.n0 * s.cost_low_s + e.n1 * (s.cost_high_s + s.cost_low_s);
  e.high_only_variance = e.v_high * s.cost_high_s / e.cost_s;
  e.high_only_cost_s = e.v_high * s.cost_high_s / e.variance;
  e.optimal_n0_per_n1 = std::sqrt(e.v0 / s.cost_low_s) / std::sqrt(e.v1 / (s.cost_high_s + s.cost_low_s));
  e.optimal_cost_ratio = e.v_high * s.cost_high_s /
                         std::pow(std::sqrt(e.v0 * s.cost_low_s) + std::sqrt(e.v1 * (s.cost_high_s + s.cost_low_s)), 2);
  OT::Sample pairs(e.n1, 2);
  for (std::size_t i = 0; i < e.n1; ++i) pairs(i, 0) = s.pair_low[i], pairs(i, 1) = s.pair_high[i];
  e.correlation = pairs.computePearsonCorrelation()(0, 1);
  return e;
}

TwoLevelSamples load_two_levels(const std::string& db_file, const std::string& low_campaign,
                                const std::string& high_campaign, const std::string& metric, double cost_low_s,
                                double cost_high_s) {
  const TrainingData low = load_training_data(db_file, low_campaign, metric, 2);
  const TrainingData high = load_training_data(db_file, high_campaign, metric, 2);
  if (low.inputs != high.inputs)
    throw InputError(db_file, "--high", "campaigns '" + low.campaign + "' and '" + high.campaign +
                                            "' have different parameters; the levels must share their inputs");
  std::map<std::vector<double>, double> high_at;
  for (std::size_t i = 0; i < high.x.size(); ++i) high_at[high.x[i]] = high.y[i];
  TwoLevelSamples s;
  for (std::size_t i = 0; i < low.x.size(); ++i) {
    const auto it = high_at.find(low.x[i]);
    if (it == high_at.end()) {
      s.low_only.push_back(low.y[i]);
    } else {
      s.pair_low.push_back(low.y[i]);
      s.pair_high.push_back(it->second);
    }
  }
  if (s.pair_low.size() < 2)
    throw InputError(db_file, "--high",
                     "campaigns '" + low.campaign + "' and '" + high.campaign + "' share " +
                         std::to_string(s.pair_low.size()) +
                         " finished point(s); the correction term needs at least 2 (give the high campaign a "
                         "design whose points the low one also runs)");
  store::CampaignStore db(db_file, /*read_only=*/true);
  s.cost_low_s = cost_low_s > 0 ? cost_low_s : db.summary(low.campaign_id).mean_wall_s;
  s.cost_high_s = cost_high_s > 0 ? cost_high_s : db.summary(high.campaign_id).mean_wall_s;
  if (!(s.cost_low_s > 0) || !(s.cost_high_s > 0))
    throw InputError(db_file, "--cost-low", "the runs record no wall time; give --cost-low and --cost-high (s)");
  return s;
}

}  // namespace flume::surrogate
