// `flume export RUN_DIR --csv DIR`: a run's records from result.h5 as CSV files, one per kind of instrument
// (docs/results.md lists the columns and their units).
#pragma once
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace flume::report {

void add_export_command(CLI::App& app);

// Writes DIR/<kind>.csv for each of gauges, probes, loads, sections, debris and diagnostics the file holds;
// returns the files written.
std::vector<std::string> export_run_csv(const std::string& h5_file, const std::string& out_dir);

}  // namespace flume::report
