// The study's debris metrics from the recorded trajectories (issue 4; the paper's section 5 and eq. 59).
#pragma once
#include <map>
#include <string>

#include "solver/rigid/debris_recorder.h"
#include "solver/scene.h"

namespace flume {

// Per debris k (named as in the scene, D1..D6 for the Waseda layout), in the basin frame (x downstream,
// y across), displacements from the initial centre:
//   <k>.initial_x_m, .initial_y_m          the initial centre
//   <k>.runup_x_m, .runup_y_m, .runup_time_s   the centre when the longitudinal displacement peaks (run-up)
//   <k>.rest_x_m, .rest_y_m                the centre at the end of the run (rest after drawdown, where
//                                          .at_rest says it has come to rest)
//   <k>.longitudinal_max_m, .longitudinal_rest_m   x displacement at run-up and at rest
//   <k>.lateral_runup_m, .lateral_rest_m   y displacement (signed) at run-up and at rest
//   <k>.spreading_runup_deg, .spreading_rest_deg   atan2(lateral, longitudinal) (eq. 59's angle, signed)
//   <k>.final_speed_m_s                    speed at the end (a debris still moving has not come to rest)
//   <k>.moving_until_s                     the last recorded time its speed exceeded debris.rest_speed_m_s
//   <k>.at_rest                            1 when it was slower than that over the record's last
//                                          debris.rest_hold_s (so "rest" is a rest position), else 0
//   <k>.dammed                             1 when it ends within `dam_gap_m` of an obstacle column's face
//   <k>.accel_peak_force_n, .accel_peak_force_30hz_n   peak |m a| at the solver's rate and at 30 Hz
// and per run debris.mobilised_count (longitudinal_max above half the box's extent along x) and
// debris.at_rest_count.
std::map<std::string, double> debris_metrics(const Scene& scene, const DebrisRecorder& recorder,
                                             double dam_gap_m);

}  // namespace flume
