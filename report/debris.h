// The debris-spreading analysis: positions of every debris in every run, the spreading and displacement
// guidelines, and probabilities over the runs. Metric names are the solver's contract, per debris
// k = 1..6: D<k>.initial_x_m, .initial_y_m, .runup_x_m, .runup_y_m, .rest_x_m, .rest_y_m,
// .longitudinal_max_m, .longitudinal_rest_m, .lateral_runup_m, .lateral_rest_m, .spreading_runup_deg,
// .spreading_rest_deg, .dammed, .at_rest, .accel_peak_force_n, .accel_peak_force_30hz_n.
//   Naito et al. (2014): spreading angle within +-22.5 degrees (a conservative design guideline).
//   Nistor et al. (2017), as eq. 59 of the comparative study: +-(3.69 + 0.80 N) degrees, N debris.
//   Nistor et al. (2017), eq. 58: median longitudinal displacement 3.58 - 0.09 N metres.
#pragma once
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "report/campaign_data.h"
#include "report/geometry.h"
#include "report/statistics.h"

namespace flume::report {

constexpr double kNaitoSpreadingDeg = 22.5;
inline double nistor_spreading_deg(int n_debris) { return 3.69 + 0.80 * n_debris; }
inline double nistor_longitudinal_m(int n_debris) { return 3.58 - 0.09 * n_debris; }

struct DebrisState {
  int k = 0;
  double x0 = 0, y0 = 0, x_runup = 0, y_runup = 0, x_rest = 0, y_rest = 0;
  double longitudinal_max = 0, longitudinal_rest = 0;
  double spreading_runup = 0, spreading_rest = 0;  // degrees, signed
  bool dammed = false;
  int at_rest = -1;  // 1: at rest at the end of its run (D<k>.at_rest), 0: still moving, -1: not recorded
};

struct DebrisRun {
  std::size_t row = 0;  // index into CampaignData::rows
  std::vector<DebrisState> debris;
};

// The debris of one run's metrics, k = 1, 2, ... while D<k>.runup_x_m is there; a debris lacking one of
// its positions is left out. Angles and displacements missing from the metrics are computed from the
// positions (spreading = atan2(lateral, longitudinal), as eq. 59 defines it).
std::vector<DebrisState> debris_of(const std::map<std::string, double>& metrics);

// Per-run debris summaries, added to the report's metrics (names start with "debris."):
//   debris.count, debris.spreading_runup_max_abs_deg, debris.spreading_rest_max_abs_deg,
//   debris.longitudinal_max_median_m, debris.longitudinal_rest_median_m,
//   debris.runout_runup_max_m, debris.runout_rest_max_m (farthest debris past the quay wall),
//   debris.dammed_count, and debris.moving_count (debris not at rest at the end) where every debris has
//   D<k>.at_rest.
std::map<std::string, double> derived_debris_metrics(const std::vector<DebrisState>& debris, double quay_x_m);

struct Probability {
  std::string what;
  std::size_t count = 0, n = 0;
  Estimate p;
};

struct PresenceMap {
  std::vector<double> x_edges, y_edges;
  std::vector<double> runup, rest;  // fraction of runs with a debris centre in cell (j * nx + i)
};

struct DebrisGroup {
  std::string layout;
  int n_debris = 0;
  ApronGeometry geometry;
  std::vector<DebrisRun> runs;
  double apex_x = 0, apex_y = 0;  // mean initial centroid of the debris field, the cones' apex
  std::vector<Probability> probabilities;
  PresenceMap presence;
  EcdfBand runout_runup, runout_rest;  // run-out of the farthest debris past the quay, per run
};

struct DebrisAnalysis {
  std::vector<DebrisGroup> groups;  // one per (obstacle layout, number of debris)
  std::size_t runs_with_debris = 0;
};

// Over the rows `sample` (ok runs); groups by layout and debris count.
DebrisAnalysis analyse_debris(const CampaignData& data, const std::vector<std::size_t>& sample, double cell_m,
                              const StatsOptions& opt);

}  // namespace flume::report
