// Running a scene to its end time and writing its outputs: the body of `flume run`, callable from tests.
#pragma once
#include <map>
#include <string>

#include "solver/simulation.h"

namespace flume {

struct RunOutcome {
  RunStatus status = RunStatus::kRunning;
  std::string message;
  std::map<std::string, double> metrics;
  Cost cost;
};

// Runs to scene.solver.end_time (or until unstable), writing OUT_DIR/result.h5 (+ result.xmf when there
// are snapshots) and OUT_DIR/run.json. `progress` prints a line per simulated tenth of the run to stderr.
RunOutcome run_scene(const Scene& scene, const SimulationOptions& options, const std::string& out_dir,
                     bool progress = false);

// Writes the record of a simulation (series, diagnostics, attributes) into an open result file.
namespace h5 { class RunFile; }
void write_record(h5::RunFile& file, const Scene& scene, const Record& record);

double peak_rss_mb();

}  // namespace flume
