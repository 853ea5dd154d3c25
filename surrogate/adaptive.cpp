#include "surrogate/adaptive.h"

#include <algorithm>
#include <cmath>

#include "sampling/ot_bridge.h"
#include "surrogate/ot_models.h"

namespace flume::surrogate {

Proposal propose_batch(const TrainingData& data, const AdaptiveSettings& s, const std::string& kriging_model) {
  Proposal out;
  try {
    const OT::Distribution joint = sampling::detail::make_ot_joint(data.distributions, data.correlations);
    OT::Sample x = detail::to_sample(data.x), y = detail::to_column(data.y);
    OT::KrigingResult k;
    if (kriging_model.empty())
      k = detail::fit_kriging(x, y);
    else
      detail::load_study(kriging_model, k);
    OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(s.seed * 1000003 + data.y.size()));
    OT::Sample candidates = joint.getSample(s.candidates);
    for (std::size_t b = 0; b < s.batch && candidates.getSize() > 0; ++b) {
      const OT::Sample var = k.getConditionalMarginalVariance(candidates);
      OT::Sample mean;
      if (s.criterion == Criterion::kExceedance) mean = k.getConditionalMean(candidates);
      std::size_t best = 0;
      double best_score = s.criterion == Criterion::kVariance ? -1.0 : HUGE_VAL;
      for (std::size_t i = 0; i < candidates.getSize(); ++i) {
        const double v = std::max(var(i, 0), 0.0);
        if (s.criterion == Criterion::kVariance) {
          if (v > best_score) best_score = v, best = i;
        } else {
          const double u = std::abs(mean(i, 0) - s.threshold) / std::sqrt(std::max(v, 1e-300));
          if (u < best_score) best_score = u, best = i;
        }
      }
      const OT::Point pick = candidates[best];
      out.points.emplace_back(pick.begin(), pick.end());
      out.score.push_back(best_score);
      // Kriging believer: the pick joins the runs at its predicted value, the covariance unchanged.
      x.add(pick);
      y.add(k.getConditionalMean(pick));
      k = detail::refit_kriging(k, x, y);
      candidates.erase(best);
    }
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
  return out;
}

}  // namespace flume::surrogate
