// Peak and arrival of one gauge record: the solver's per-run metrics (solver/run_output.cpp) and the
// report's `flume gauges` use this one definition.
#pragma once
#include <vector>

namespace flume {

// Peak and arrival of one gauge record (non-finite samples are skipped). The arrival is the first time the
// record rises `threshold` above its first finite reading (0 in still water; the ground's height where the
// gauge starts dry, as on an apron); arrived is false when it never does.
struct GaugeSummary {
  bool has_peak = false, arrived = false;
  double peak = 0, peak_time = 0, first = 0, arrival_time = 0;
};
GaugeSummary summarize_gauge(const std::vector<double>& time, const std::vector<double>& value, double threshold);

// Peak, its time and impulse of a pressure probe's record (Pa, s, Pa s). Each sample is the mean over the
// interval since the one before it (solver/pressure_probes.h), so the impulse is the sum of sample x interval,
// exactly the integral of the per-step readings. Non-finite samples are skipped; an empty record has all 0.
struct PressureSummary {
  double peak = 0, peak_time = 0, impulse = 0;
};
PressureSummary summarize_pressure(const std::vector<double>& time, const std::vector<double>& value);

}  // namespace flume
