// Multi-fidelity Monte Carlo (Peherstorfer, Willcox & Gunzburger 2016, SIAM J. Sci. Comput. 38(5), A3163-A3194):
// the mean of the highest-fidelity metric Y_1 from K >= 2 levels ordered high to low, on nested samples (the
// N_1 points of level 1 are among the N_2 >= N_1 of level 2, and so on):
//   estimate = mean_{N_1} Y_1 + sum_{k>=2} alpha_k (mean_{N_k} Y_k - mean_{N_{k-1}} Y_k)
//   variance = sigma_1^2 / N_1 + sum_{k>=2} (1/N_{k-1} - 1/N_k)(alpha_k^2 sigma_k^2 - 2 alpha_k rho_1k sigma_1 sigma_k)
//              (their Lemma 3.3), cost = sum_k N_k c_k
// with the optimal weights alpha_k = rho_1k sigma_1 / sigma_k (Theorem 3.4), the regression coefficient of Y_1 on
// Y_k. sigma_k and rho_1k come from the N_1 points where every level ran. The optimal allocation for a budget
// (Theorem 3.4) is N_k = r_k N_1, r_k = sqrt(c_1 (rho_1k^2 - rho_1,k+1^2) / (c_k (1 - rho_12^2))), rho_1,K+1 = 0;
// its variance is sigma_1^2 / budget (sum_k sqrt(c_k (rho_1k^2 - rho_1,k+1^2)))^2 (Corollary 3.5), so high
// runs alone cost c_1 / (that sum)^2 times as much for one variance. It holds when the levels are ordered:
// |rho_11| > |rho_12| > ... > |rho_1K| and c_{k-1} / c_k > (rho_1,k-1^2 - rho_1k^2) / (rho_1k^2 - rho_1,k+1^2);
// otherwise the best subset of the levels that is (their Algorithm 1) is named instead.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace flume::surrogate {

struct MfmcSamples {
  // y[k][i]: level k (0 = highest fidelity) at its i-th point; the first y[k-1].size() points of level k are
  // those of level k - 1, in the same order.
  std::vector<std::vector<double>> y;
  std::vector<double> cost_s;  // per run, per level
  std::vector<std::string> names;
  std::vector<std::size_t> dropped;  // finished runs of a level left out as the next level lacks their point
};

struct MfmcLevel {
  std::size_t n = 0;
  double sigma = 0;     // standard deviation over the N_1 common points
  double rho = 0;       // correlation with level 1 there (1 for level 1)
  double alpha = 0;     // the weight used (1 for level 1)
  double alpha_opt = 0;  // rho_1k sigma_1 / sigma_k
  double r_opt = 0;     // optimal N_k / N_1 (0 where the ordering fails)
};

struct MfmcEstimate {
  std::vector<MfmcLevel> levels;
  double mean = 0, variance = 0, lo = 0, hi = 0;  // estimator, its variance (Lemma 3.3), normal interval
  double cost_s = 0;                              // sum_k N_k c_k
  double high_only_variance = 0;                  // of high runs alone at the same cost
  double high_only_cost_s = 0;                    // high runs alone for the same variance
  bool ordered = true;         // Theorem 3.4's conditions hold for all K levels
  std::string ordering_note;   // which condition fails, if one does
  double optimal_cost_ratio = 0;  // high alone over MFMC at the optimal allocation, same variance (all K levels
                                  // if ordered, else the best ordered subset)
  std::vector<std::size_t> optimal_subset;  // the levels (0-based) that ratio uses
};

// The estimate with the optimal weights, or with `alpha` (one per level, alpha[0] ignored) when given.
// Throws std::invalid_argument for fewer than 2 levels or 2 common points, samples that are not nested
// (N_k < N_{k-1}), non-positive costs or a level constant over the common points.
MfmcEstimate mfmc_estimate(const MfmcSamples& s, double confidence = 0.95, const std::vector<double>& alpha = {});

// Variance of the estimator (Lemma 3.3) for sample sizes n, weights alpha and level statistics sigma, rho.
double mfmc_variance(const std::vector<double>& n, const std::vector<double>& alpha, const std::vector<double>& sigma,
                     const std::vector<double>& rho);

// Theorem 3.4 for the levels `subset` (0-based, increasing, starting at 0): r_k per level of the subset, or an
// empty vector with `why` set when the ordering conditions fail.
std::vector<double> mfmc_optimal_ratios(const std::vector<double>& cost, const std::vector<double>& rho,
                                        const std::vector<std::size_t>& subset, std::string* why = nullptr);

// High runs alone over MFMC at the optimal allocation of `subset`, for one variance: c_1 / (sum_k sqrt(c_k
// (rho_1k^2 - rho_1,k+1^2)))^2.
double mfmc_optimal_cost_ratio(const std::vector<double>& cost, const std::vector<double>& rho,
                               const std::vector<std::size_t>& subset);

// Nests the finished runs of campaigns (high to low fidelity) of a store by their parameter values; costs are
// the campaigns' mean wall times where not given (> 0). Throws flume::InputError (file, option) when campaigns
// differ in parameters or fewer than 2 points ran at every level.
MfmcSamples load_levels(const std::string& db_file, const std::vector<std::string>& campaigns, const std::string& metric,
                        const std::vector<double>& cost_s = {});

}  // namespace flume::surrogate
