// The calibration spec's fields, described once (common/input/fields.h): calibration/spec.cpp reads every
// value through them, `flume schema calibration` prints them as a JSON Schema, docs/calibration-spec.md is
// generated from them.
#pragma once
#include "common/input/fields.h"

namespace flume::calibration {

const input::ObjectDoc& calibration_doc();  // the top level of a calibration spec

}  // namespace flume::calibration
