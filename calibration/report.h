// What a calibration leaves in OUT: calibration.json (best parameters, objective and its terms, starts,
// profiles, identifiability, evaluation counts and cost), fit.svg (fitted, start and target records of every
// gauge on one figure), fit.csv, profiles.svg and history.svg (objective per evaluation and start).
#pragma once
#include <vector>

#include "calibration/calibrate.h"
#include "calibration/objective.h"
#include "store/db/campaign_store.h"

namespace flume::calibration {

void write_report(const CalibrationSpec& spec, const CalibrateOptions& options, const Objective& objective,
                  const CalibrationResult& result, const std::vector<store::Evaluation>& history);

}  // namespace flume::calibration
