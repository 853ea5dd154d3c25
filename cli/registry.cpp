#include "cli/registry.h"

#include "calibration/commands.h"
#include "cli/schema.h"
#include "campaigns/commands.h"
#include "report/export.h"
#include "report/gauges.h"
#include "report/paths.h"
#include "report/report.h"
#include "solver/commands.h"
#include "study/tradeoff.h"
#include "surrogate/commands.h"

namespace flume::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> list = {
      {"run", "run a scene: DIR/result.h5 and DIR/run.json", add_run_command, nullptr},
      {"bench", "time N steps of a scene; JSON on stdout", add_bench_command, nullptr},
      {"check", "validate a scene and print a summary", add_check_command, nullptr},
      {"campaign", "run, follow and export uncertainty campaigns", add_campaign_command, nullptr},
      {"report", "HTML/JSON/CSV report of a campaign", report::add_report_command, nullptr},
      {"debris-paths", "top-down debris paths of runs, with the Naito and Nistor guidelines",
       report::add_debris_paths_command, nullptr},
      {"gauges", "gauge records of runs, their peaks and arrivals", report::add_gauges_command, nullptr},
      {"export", "a run's gauges, probes, loads, sections and debris as CSV files", report::add_export_command,
       nullptr},
      {"model", "analytic stand-ins for `flume run` (campaign tests)", add_model_command, nullptr},
      {"study", "error against cost over fidelity settings, Pareto front", study::add_study_command, nullptr},
      {"calibrate", "fit scene parameters to measured gauges", calibration::add_calibrate_command, nullptr},
      {"schema", "JSON Schema or Markdown reference of the scene, campaign, calibration and study files",
       add_schema_command, nullptr},
      {"surrogate", "polynomial chaos and kriging surrogates of a campaign's runs, Sobol' indices, posteriors",
       nullptr, surrogate_main},
  };
  return list;
}

}  // namespace flume::cli
