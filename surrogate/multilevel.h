// Multi-fidelity: the two-level Monte Carlo estimator (Giles 2008, Oper. Res. 56(3), eqs. (1)-(5)) of the
// mean of a high-fidelity metric from a cheap campaign (low level) and an expensive one (high level) over the
// same inputs:
//   E[Y_H] ~ mean over N0 low runs of Y_L  +  mean over N1 paired runs of (Y_H - Y_L)
//   Var    = V0 / N0 + V1 / N1,  V0 = Var Y_L,  V1 = Var (Y_H - Y_L)
//   cost   = N0 c_L + N1 (c_H + c_L)
// Pairs are runs of the two campaigns with the same parameter values; the level-0 sum uses the low runs
// without a pair (independent of the correction term). Set against it: high-level runs alone at the same
// cost (variance V_H c_H / cost), the cost high runs alone need for the same variance, and the allocation
// that minimises the variance for that cost, N_l proportional to sqrt(V_l / C_l) (Giles 2008, eq. (6)).
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace flume::surrogate {

struct TwoLevelSamples {
  std::vector<double> low_only;              // Y_L at inputs without a high run
  std::vector<double> pair_low, pair_high;   // Y_L and Y_H at the same inputs
  double cost_low_s = 0, cost_high_s = 0;    // per run
};

struct TwoLevelEstimate {
  std::size_t n0 = 0, n1 = 0;
  double mean = 0, variance = 0, lo = 0, hi = 0;  // estimator, its variance and normal interval
  double v0 = 0, v1 = 0, v_high = 0;               // Var Y_L, Var (Y_H - Y_L), Var Y_H
  double cost_s = 0;                               // spent
  double high_only_variance = 0;                   // of high runs alone at the same cost
  double high_only_cost_s = 0;                     // high runs alone for the same variance
  double optimal_n0_per_n1 = 0;                    // sqrt(V0 / c_L) / sqrt(V1 / (c_H + c_L))
  double optimal_cost_ratio = 0;  // high alone over two levels for one variance, at that allocation (eq. (6)):
                                  // V_H c_H / (sqrt(V0 c_L) + sqrt(V1 (c_H + c_L)))^2
  double correlation = 0;         // of Y_L and Y_H over the pairs
};

// Throws std::invalid_argument with fewer than 2 values in either term or non-positive costs.
TwoLevelEstimate two_level_estimate(const TwoLevelSamples& s, double confidence = 0.95);

// Pairs the finished runs of two campaigns of a store by their parameter values; the costs are the
// campaigns' mean wall times unless given (> 0). Throws flume::InputError (file, option) when the
// campaigns differ in parameters or share fewer than 2 points.
TwoLevelSamples load_two_levels(const std::string& db_file, const std::string& low_campaign,
                                const std::string& high_campaign, const std::string& metric, double cost_low_s = 0,
                                double cost_high_s = 0);

}  // namespace flume::surrogate
