// The scene file's fields, described once (common/input/fields.h): solver/scene.cpp reads every value through
// them, `flume schema scene` prints them as a JSON Schema, and docs/scene.md is generated from them.
#pragma once
#include "common/input/fields.h"

namespace flume {

const input::ObjectDoc& scene_doc();  // the top level of a scene file

// Sections read on their own (a basin scene's generator reads them before the scene proper).
const input::ObjectDoc& basin_doc();
const input::ObjectDoc& reservoir_doc();
const input::ObjectDoc& obstacles_doc();
const input::ObjectDoc& debris_doc();

}  // namespace flume
