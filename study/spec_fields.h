// The study spec's fields (`flume study tradeoff`), described once (common/input/fields.h):
// study/tradeoff.cpp reads them through these descriptions (name, description, scene, overrides and run
// through the campaign parser, with the campaign's descriptions), `flume schema study` prints them as a JSON
// Schema, and docs/study-spec.md is generated from them.
#pragma once
#include "common/input/fields.h"

namespace flume::study {

const input::ObjectDoc& study_doc();  // the top level of a study spec
const input::ObjectDoc& study_outputs_doc();
const input::ObjectDoc& study_reference_doc();

}  // namespace flume::study
