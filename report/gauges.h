// `flume gauges RUN_DIR[=LABEL] ... --out FILE.svg`: the gauge records of finished runs, one panel per gauge
// and one line per run, with each record's peak and arrival on stdout (report/gauges.cpp).
#pragma once
#include <string>
#include <vector>

namespace flume::report {

int gauges_main(int argc, char** argv);

// Peak and arrival of one gauge record (non-finite samples are skipped). The arrival is the first time the
// record rises `threshold` above its first finite reading (0 in still water; the ground's height where the
// gauge starts dry), as compute_metrics has it for run.json; arrived is false when it never does.
struct GaugeSummary {
  bool has_peak = false, arrived = false;
  double peak = 0, peak_time = 0, first = 0, arrival_time = 0;
};
GaugeSummary summarize_gauge(const std::vector<double>& time, const std::vector<double>& value, double threshold);

// Gauge names in natural order: WG2 before WG10 (the result file keeps no creation order).
void sort_gauge_names(std::vector<std::string>& names);

}  // namespace flume::report
