// A calibration's spec as the store keeps it (its identity, CalibrationSpec::canonical), parsed back into a
// CalibrationSpec: what reads a calibration's evaluations after the fact (`flume surrogate posterior`)
// compares the runs with the very target records and window `flume calibrate` fitted.
#pragma once
#include <string>

#include "calibration/spec.h"

namespace flume::calibration {

// Throws InputError naming `label` when a target file is gone or its content is no longer the one the
// calibration fitted (its stored hash), or for what parse_calibration_spec refuses (a scene no longer there).
CalibrationSpec parse_stored_calibration_spec(const std::string& stored_json, const std::string& label);

}  // namespace flume::calibration
