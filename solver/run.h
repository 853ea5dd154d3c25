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

// Checkpoints of a run (solver/checkpoint.h): OUT_DIR/checkpoint.bin.
struct CheckpointOptions {
  double every_s = 0;   // > 0: write one every this many wall-clock seconds, and one at the end
  bool resume = false;  // start from OUT_DIR/checkpoint.bin instead of t = 0
};

// How often (wall-clock seconds) a run pushes its record so far into result.h5.part: a run killed outright
// (SIGKILL, out of memory, a node lost) leaves a file that opens in any HDF5 reader and holds the series up to
// its last flush. Each flush appends only the new rows and costs milliseconds.
constexpr double kDefaultFlushEvery_s = 10.0;

// SIGTERM and SIGINT end `flume run` cleanly: the step loop stops after the step in progress, the record is
// written, result.h5 (renamed from .part) and run.json say status "killed", a checkpoint is written when
// checkpoints were asked for, and the command exits 128 + the signal (130 for SIGINT, 143 for SIGTERM), as a
// shell reports a killed program. install_stop_handlers() is for the command; run_scene only reads the flag.
void install_stop_handlers();
int stop_signal();  // the signal that asked the run to stop, or 0

// Runs to scene.solver.end_time (or until unstable, or until stop_signal()), writing OUT_DIR/result.h5 (+ result.xmf when there
// are snapshots) and OUT_DIR/run.json. `progress` prints a line per simulated tenth of the run to stderr.
// With checkpoints, a run killed at any point resumes from its last checkpoint (`resume`) and finishes as the
// uninterrupted run would; a finished run resumes to a later end time. Scenes with snapshots are refused
// (the snapshots before the checkpoint would be lost).
RunOutcome run_scene(const Scene& scene, const SimulationOptions& options, const std::string& out_dir,
                     bool progress = false, const CheckpointOptions& checkpoints = {},
                     double flush_every_s = kDefaultFlushEvery_s);

// Writes the record of a simulation (series, diagnostics, attributes) into an open result file.
namespace h5 { class RunFile; }
void write_record(h5::RunFile& file, const Scene& scene, const Record& record);

double peak_rss_mb();

}  // namespace flume
