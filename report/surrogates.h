// The report's surrogate section: each stored surrogate of the campaign (`flume surrogate fit`) with its
// quality (Q2, predicted against observed), its Sobol' indices beside the sampling estimates, and the
// exceedance curves it gives with their bands. Read from the store's surrogates table; no OpenTURNS here.
#pragma once
#include <cstddef>
#include <sstream>
#include <string>
#include <vector>

#include "report/statistics.h"

namespace flume::report {

struct Report;

struct SurrogateSummary {
  std::string metric, kind, created;
  std::size_t n_train = 0, n_holdout = 0, folds = 0;
  int degree = 0;
  std::size_t terms = 0;
  double q2_cv = 0, q2_holdout = 0;  // NaN when not computed
  std::vector<double> cv_observed, cv_predicted, holdout_observed, holdout_predicted;
  std::vector<std::string> inputs;
  std::vector<Estimate> first, total;  // chaos only
  double confidence = 0.95;
  double mean = 0, std = 0;
  std::vector<double> thresholds, p, p_lo, p_hi;
  std::size_t replicates = 0;
  std::size_t mc_size = 0;      // input points of the central curve
  std::size_t band_points = 0;  // input points of each replicate or realisation (0: not recorded)
  // Fitted where a metric exists only (docs/surrogates.md): that metric and its classifier, in words; empty
  // for a fit over every run.
  std::string condition;
};

// The campaign's stored surrogates (none for a store without the table). A malformed row is reported as an
// InputError naming the file and the row.
std::vector<SurrogateSummary> load_surrogates(const std::string& db_file, std::int64_t campaign);

void surrogates_section(std::ostringstream& h, const Report& r);

}  // namespace flume::report
