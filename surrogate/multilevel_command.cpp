#include "surrogate/multilevel_command.h"

#include <cmath>
#include <cstdio>

#include "surrogate/mfmc.h"
#include "surrogate/multilevel.h"

namespace flume::surrogate {
namespace {

void print_giles(const std::string& db_file, const std::vector<std::string>& levels, const std::vector<double>& costs,
                 const std::string& metric, double confidence) {
  const auto samples = load_two_levels(db_file, levels[1], levels[0], metric, costs.empty() ? 0 : costs[1],
                                       costs.empty() ? 0 : costs[0]);
  if (samples.low_only.size() < 2) {  // its first term is over the low runs without a pair
    std::printf("two-level Monte Carlo (Giles 2008) of E[%s]: not defined, %zu low-only run(s) (needs 2)\n",
                metric.c_str(), samples.low_only.size());
    return;
  }
  const auto e = two_level_estimate(samples, confidence);
  std::printf("two-level Monte Carlo (Giles 2008) of E[%s]: %.6g, %.0f %% interval [%.6g, %.6g], std %.4g\n",
              metric.c_str(), e.mean, 100 * confidence, e.lo, e.hi, std::sqrt(e.variance));
  std::printf("runs: %zu low only, %zu pairs; cost per run %.4g s low, %.4g s high; spent %.4g s\n", e.n0, e.n1,
              samples.cost_low_s, samples.cost_high_s, e.cost_s);
  std::printf("variances: low %.4g, correction %.4g, high %.4g; correlation of the levels over the pairs %.4f\n", e.v0,
              e.v1, e.v_high, e.correlation);
  std::printf("high runs alone at the same cost: std %.4g (%.2f times the two-level std); for the same std they "
              "would cost %.4g s (%.2f times)\n",
              std::sqrt(e.high_only_variance), std::sqrt(e.high_only_variance / e.variance), e.high_only_cost_s,
              e.high_only_cost_s / e.cost_s);
  std::printf("optimal allocation: %.3g low-only runs per pair; with it high runs alone would cost %.2f times the "
              "two levels for the same std\n",
              e.optimal_n0_per_n1, e.optimal_cost_ratio);
}

void print_mfmc_line(const char* what, const std::string& metric, const MfmcEstimate& e, double confidence) {
  std::printf("%s of E[%s]: %.6g, %.0f %% interval [%.6g, %.6g], std %.4g; spent %.4g s, high runs alone for the "
              "same std %.4g s (%.2f times)\n",
              what, metric.c_str(), e.mean, 100 * confidence, e.lo, e.hi, std::sqrt(e.variance), e.cost_s,
              e.high_only_cost_s, e.high_only_cost_s / e.cost_s);
}

}  // namespace

void print_multilevel(const std::string& db_file, const std::vector<std::string>& levels,
                      const std::vector<double>& costs, const std::string& metric, double confidence) {
  if (levels.size() == 2) print_giles(db_file, levels, costs, metric, confidence);
  const MfmcSamples s = load_levels(db_file, levels, metric, costs);
  const MfmcEstimate e = mfmc_estimate(s, confidence);
  const MfmcEstimate unit = mfmc_estimate(s, confidence, std::vector<double>(levels.size(), 1.0));
  std::printf("multi-fidelity Monte Carlo (Peherstorfer et al. 2016), %zu nested levels, statistics over the %zu "
              "points every level ran:\n",
              levels.size(), e.levels[0].n);
  std::printf("  level,campaign,runs,cost_s,std,rho_1k,alpha_opt,r_opt\n");
  for (std::size_t k = 0; k < levels.size(); ++k) {
    const MfmcLevel& l = e.levels[k];
    std::printf("  %zu,%s,%zu,%.4g,%.4g,%.4f,%.4f,%.4g\n", k + 1, levels[k].c_str(), l.n, s.cost_s[k], l.sigma, l.rho,
                l.alpha_opt, l.r_opt);
    if (s.dropped[k])
      std::printf("  (%zu finished run(s) of %s left out: the next level has no run at their point)\n", s.dropped[k],
                  levels[k].c_str());
  }
  print_mfmc_line("MFMC, optimal weights", metric, e, confidence);
  print_mfmc_line("MFMC, unit weights", metric, unit, confidence);
  if (e.ordered)
    std::printf("optimal allocation (Theorem 3.4): N_k / N_1 as r_opt above; high runs alone would cost %.2f times "
                "MFMC for the same std\n",
                e.optimal_cost_ratio);
  else {
    std::printf("the levels fail the ordering of Theorem 3.4 (%s); the best ordered subset, levels",
                e.ordering_note.c_str());
    for (std::size_t k : e.optimal_subset) std::printf(" %zu", k + 1);
    std::printf(", at its optimal allocation: high runs alone would cost %.2f times it for the same std\n",
                e.optimal_cost_ratio);
  }
}

}  // namespace flume::surrogate
