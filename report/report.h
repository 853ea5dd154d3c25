// `flume report`: the probabilistic report of a campaign (docs/report.md says how to read it).
//   build_report   reads the store and computes every statistic (no files written)
//   write_report   writes report.html (self-contained: inline SVG and CSS, one inline check script, nothing
//                  fetched), summary.json and the CSV tables into the output folder
#pragma once

namespace CLI {
class App;
}
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "report/campaign_data.h"
#include "report/debris.h"
#include "report/sensitivity.h"
#include "report/statistics.h"
#include "report/surrogates.h"

namespace flume::report {

struct ReportOptions {
  std::string db_file;
  std::string campaign;  // empty: the store's only campaign
  std::string out_dir;
  std::map<std::string, std::vector<double>> thresholds;  // metric -> exceedance thresholds
  std::map<std::string, double> ci_widths;                // metric -> target width of the mean's interval
  StatsOptions stats;
  double cell_m = 0.25;  // presence-map cell size
  std::size_t map_runs =
      1000;  // runs whose debris are drawn on the apron map (all runs enter the statistics)
};

struct MetricReport {
  std::string name;
  bool headline = true;            // a per-debris metric (D<k>.*) is tabulated only
  std::size_t missing = 0;         // ok runs of the sample without a finite value
  std::optional<Summary> summary;  // none when fewer than 2 values
  EcdfBand ecdf;
  std::vector<double> values;  // in design order, over the sample's ok runs that have the metric
  RunningMean convergence;
  double target_width = 0;    // of the mean's confidence interval
  std::string target_source;  // "--ci-width" or "default: 10 % of |mean|" ...
  std::size_t runs_needed = 0;
  std::optional<SobolResult> sobol;
  std::optional<CorrelationResult> correlations;
  std::string sensitivity_note;  // why there is none, or what it rests on
};

struct Report {
  CampaignData data;
  ReportOptions options;
  std::vector<std::size_t> sample;                 // rows (design points) the distribution statistics rest on
  std::string sample_note;                         // which rows and why
  std::size_t sample_ok = 0;                       // of those, ok runs
  std::map<store::RunStatus, std::size_t> counts;  // per distinct run
  std::vector<std::size_t> not_ok;  // rows of distinct runs that did not end ok (pending included)
  std::vector<std::string> sensitivity_inputs;  // parameter paths (text parameters coded by first appearance)
  std::vector<MetricReport> metrics;
  DebrisAnalysis debris;
  std::vector<SurrogateSummary> surrogates;  // stored by `flume surrogate fit`
};

// Throws flume::InputError for a bad option (unknown metric in thresholds, ...) or store.
Report build_report(const ReportOptions& options);

void write_report(const Report& report);

// The HTML page alone (for tests).
std::string render_html(const Report& report);

// `flume report --db FILE --campaign NAME --out DIR [options]` on the command line (common/command.h).
void add_report_command(CLI::App& app);

}  // namespace flume::report
