// `flume gauges RUN_DIR[=LABEL] ... --out FILE.svg`: the gauge records of finished runs, one panel per gauge
// and one line per run, with each record's peak and arrival on stdout (report/gauges.cpp).
#pragma once
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace flume::report {

void add_gauges_command(CLI::App& app);

// Gauge names in natural order: WG2 before WG10 (the result file keeps no creation order).
void sort_gauge_names(std::vector<std::string>& names);

}  // namespace flume::report
