// Sensitivity of one output to the campaign's inputs, computed by OpenTURNS on the stored design.
//   Saltelli design (rows A, B, then A with column i from B, N rows each): first-order and total Sobol'
//   indices by the Martinez estimator (OT::MartinezSensitivityAlgorithm), bootstrap confidence intervals.
//   Any other design: Spearman rank correlation and partial rank correlation (OT::CorrelationAnalysis),
//   percentile-bootstrap confidence intervals.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "report/statistics.h"

namespace flume::report {

struct SobolResult {
  std::vector<Estimate> first, total;  // one per input
  std::size_t base_size = 0;           // N used
  std::size_t base_dropped = 0;        // base rows left out because a run of their block failed
};

// `inputs` has N * (d + 2) rows of d values in Saltelli order, `output` the matching values (NaN: the run
// failed or lacks the metric; its whole block row i of every matrix is then left out). Throws
// std::invalid_argument when fewer than 4 complete base rows remain.
SobolResult sobol_indices(const std::vector<std::vector<double>>& inputs, const std::vector<double>& output,
                          std::size_t base_size, const StatsOptions& opt);

struct CorrelationResult {
  std::vector<Estimate> spearman, prcc;  // one per input
  std::size_t n = 0;
};

// Rows with a NaN output are left out; an input that is constant over the rows gets NaN coefficients.
CorrelationResult rank_correlations(const std::vector<std::vector<double>>& inputs,
                                    const std::vector<double>& output, const StatsOptions& opt);

}  // namespace flume::report
