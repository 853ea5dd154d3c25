// Internal to flume_sampling: plain distribution structs -> OpenTURNS objects.
#pragma once
#include <openturns/OT.hxx>

#include "sampling/distribution.h"

namespace flume::sampling::detail {

OT::Distribution make_ot_distribution(const Distribution& d);

}  // namespace flume::sampling::detail
