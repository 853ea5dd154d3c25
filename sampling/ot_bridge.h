// Internal to flume_sampling: plain distribution structs -> OpenTURNS objects.
#pragma once
#include <openturns/OT.hxx>

#include "sampling/design.h"
#include "sampling/distribution.h"

namespace flume::sampling::detail {

OT::Distribution make_ot_distribution(const Distribution& d);

// The parameters' joint law: the marginals under a normal copula of the given rank correlations (independent
// when there are none). Throws std::invalid_argument when the correlation matrix is not positive definite.
OT::Distribution make_ot_joint(const std::vector<Distribution>& parameters,
                               const std::vector<RankCorrelation>& correlations);

}  // namespace flume::sampling::detail
