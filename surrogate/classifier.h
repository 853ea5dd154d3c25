// Where a metric exists: a gauge's arrival (and what is fitted given it) is defined only in the part of the
// input box where the bore reaches the gauge. A smooth surrogate cannot follow the jump at that edge, so the
// metric is fitted on the runs inside and this classifier says where inside is: a kriging of the indicator
// (1 inside, 0 outside), inside where it exceeds 1/2 (the indicator-kriging classifier of geostatistics).
// Internal to flume_surrogate (OpenTURNS types).
#pragma once
#include <openturns/OT.hxx>

#include <cstdint>
#include <vector>

#include "surrogate/fit.h"

namespace flume::surrogate {

// Asked for only when both classes have training runs. Throws OT::Exception when the indicator cannot be fitted.
ClassifierQuality classify_inside(const std::vector<std::vector<double>>& inside,
                                  const std::vector<std::vector<double>>& outside,
                                  const std::vector<std::vector<double>>& holdout_inside,
                                  const std::vector<std::vector<double>>& holdout_outside,
                                  const OT::Distribution& joint, std::size_t mc_size, std::uint64_t seed);

}  // namespace flume::surrogate
