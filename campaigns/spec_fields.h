// The campaign spec's fields, described once (common/input/fields.h): campaigns/spec.cpp reads every value
// through them, `flume schema campaign` prints them as a JSON Schema, docs/campaign-spec.md is generated from
// them.
#pragma once
#include "common/input/fields.h"

namespace flume::campaigns {

const input::ObjectDoc& campaign_doc();  // the top level of a campaign spec
const input::ObjectDoc& distribution_doc();
const input::ObjectDoc& run_settings_doc();  // `run`, shared with the calibration spec's subset

}  // namespace flume::campaigns
