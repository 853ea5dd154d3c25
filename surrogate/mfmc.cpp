#include "surrogate/mfmc.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <openturns/OT.hxx>
#include <set>
#include <stdexcept>

#include "common/errors.h"
#include "store/db/campaign_store.h"
#include "surrogate/data.h"

namespace flume::surrogate {

double mfmc_variance(const std::vector<double>& n, const std::vector<double>& alpha, const std::vector<double>& sigma,
                     const std::vector<double>& rho) {
  double v = sigma[0] * sigma[0] / n[0];
  for (std::size_t k = 1; k < n.size(); ++k)
    v += (1 / n[k - 1] - 1 / n[k]) *
         (alpha[k] * alpha[k] * sigma[k] * sigma[k] - 2 * alpha[k] * rho[k] * sigma[0] * sigma[k]);
  return v;
}

std::vector<double> mfmc_optimal_ratios(const std::vector<double>& cost, const std::vector<double>& rho,
                                        const std::vector<std::size_t>& subset, std::string* why) {
  const std::size_t m = subset.size();
  // rho^2 and cost along the subset, rho_1,m+1 = 0 closing the sums.
  std::vector<double> r2(m + 1, 0.0), c(m);
  for (std::size_t i = 0; i < m; ++i) {
    r2[i] = i == 0 ? 1.0 : rho[subset[i]] * rho[subset[i]];
    c[i] = cost[subset[i]];
  }
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return std::vector<double>{};
  };
  char buf[256];
  for (std::size_t i = 1; i < m; ++i)
    if (!(r2[i - 1] > r2[i])) {
      std::snprintf(buf, sizeof buf, "|rho| of level %zu (%.4f) is not below that of level %zu (%.4f)",
                    subset[i] + 1, std::sqrt(r2[i]), subset[i - 1] + 1, std::sqrt(r2[i - 1]));
      return fail(buf);
    }
  for (std::size_t i = 1; i < m; ++i) {
    const double need = (r2[i - 1] - r2[i]) / (r2[i] - r2[i + 1]);
    if (!(c[i - 1] / c[i] > need)) {
      std::snprintf(buf, sizeof buf,
                    "cost ratio of levels %zu and %zu is %.3g, the correlations need more than %.3g",
                    subset[i - 1] + 1, subset[i] + 1, c[i - 1] / c[i], need);
      return fail(buf);
    }
  }
  std::vector<double> r(m);
  for (std::size_t i = 0; i < m; ++i) r[i] = std::sqrt(c[0] * (r2[i] - r2[i + 1]) / (c[i] * (1 - r2[1])));
  return r;
}

double mfmc_optimal_cost_ratio(const std::vector<double>& cost, const std::vector<double>& rho,
                               const std::vector<std::size_t>& subset) {
  double sum = 0;
  for (std::size_t i = 0; i < subset.size(); ++i) {
    const double a = i == 0 ? 1.0 : rho[subset[i]] * rho[subset[i]];
    const double b = i + 1 < subset.size() ? rho[subset[i + 1]] * rho[subset[i + 1]] : 0.0;
    sum += std::sqrt(cost[subset[i]] * (a - b));
  }
  return cost[subset[0]] / (sum * sum);
}

MfmcEstimate mfmc_estimate(const MfmcSamples& s, double confidence, const std::vector<double>& alpha) {
  const std::size_t K = s.y.size();
  if (K < 2 || s.cost_s.size() != K) throw std::invalid_argument("MFMC: needs at least 2 levels, one cost each");
  if (!alpha.empty() && alpha.size() != K) throw std::invalid_argument("MFMC: one weight per level");
  const std::size_t n1 = s.y[0].size();
  if (n1 < 2) throw std::invalid_argument("MFMC: needs at least 2 points where every level ran");
  for (std::size_t k = 0; k < K; ++k) {
    if (k > 0 && s.y[k].size() < s.y[k - 1].size())
      throw std::invalid_argument("MFMC: samples not nested (level " + std::to_string(k + 1) + " has fewer points)");
    if (!(s.cost_s[k] > 0)) throw std::invalid_argument("MFMC: the costs per run must be positive");
  }
  // Level statistics over the N_1 common points: the first N_1 of every level.
  OT::Sample common(n1, K);
  for (std::size_t i = 0; i < n1; ++i)
    for (std::size_t k = 0; k < K; ++k) common(i, k) = s.y[k][i];
  const OT::CovarianceMatrix cov = common.computeCovariance();
  MfmcEstimate e;
  e.levels.resize(K);
  std::vector<double> n(K), a(K), sigma(K), rho(K);
  for (std::size_t k = 0; k < K; ++k) {
    sigma[k] = std::sqrt(cov(k, k));
    if (!(sigma[k] > 0))
      throw std::invalid_argument("MFMC: level " + std::to_string(k + 1) + " is constant over the common points");
  }
  for (std::size_t k = 0; k < K; ++k) {
    MfmcLevel& l = e.levels[k];
    l.n = s.y[k].size();
    l.sigma = sigma[k];
    l.rho = rho[k] = k == 0 ? 1.0 : cov(0, k) / (sigma[0] * sigma[k]);
    l.alpha_opt = rho[k] * sigma[0] / sigma[k];
    l.alpha = a[k] = k == 0 ? 1.0 : alpha.empty() ? l.alpha_opt : alpha[k];
    n[k] = static_cast<double>(l.n);
  }
  auto mean_of = [](const std::vector<double>& v, std::size_t count) {
    return std::accumulate(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(count), 0.0) / count;
  };
  e.mean = mean_of(s.y[0], n1);
  for (std::size_t k = 1; k < K; ++k)
    e.mean += a[k] * (mean_of(s.y[k], s.y[k].size()) - mean_of(s.y[k], s.y[k - 1].size()));
  e.variance = mfmc_variance(n, a, sigma, rho);
  const double z = OT::DistFunc::qNormal(0.5 + confidence / 2);
  e.lo = e.mean - z * std::sqrt(e.variance);
  e.hi = e.mean + z * std::sqrt(e.variance);
  for (std::size_t k = 0; k < K; ++k) e.cost_s += n[k] * s.cost_s[k];
  e.high_only_variance = sigma[0] * sigma[0] * s.cost_s[0] / e.cost_s;
  e.high_only_cost_s = sigma[0] * sigma[0] * s.cost_s[0] / e.variance;

  std::vector<std::size_t> all(K);
  std::iota(all.begin(), all.end(), 0);
  const auto r = mfmc_optimal_ratios(s.cost_s, rho, all, &e.ordering_note);
  e.ordered = !r.empty();
  for (std::size_t k = 0; k < r.size(); ++k) e.levels[k].r_opt = r[k];
  // Their Algorithm 1: the best subset (level 1 always in it) that meets the conditions; level 1 alone
  // (plain Monte Carlo, ratio 1) always does.
  e.optimal_cost_ratio = 0;
  for (std::size_t mask = 0; mask < (std::size_t{1} << (K - 1)); ++mask) {
    std::vector<std::size_t> sub{0};
    for (std::size_t k = 1; k < K; ++k)
      if (mask >> (k - 1) & 1) sub.push_back(k);
    if (mfmc_optimal_ratios(s.cost_s, rho, sub).empty()) continue;
    const double ratio = mfmc_optimal_cost_ratio(s.cost_s, rho, sub);
    if (ratio > e.optimal_cost_ratio) e.optimal_cost_ratio = ratio, e.optimal_subset = sub;
  }
  return e;
}

MfmcSamples load_levels(const std::string& db_file, const std::vector<std::string>& campaigns, const std::string& metric,
                        const std::vector<double>& cost_s) {
  const std::size_t K = campaigns.size();
  if (K < 2) throw InputError(db_file, "--levels", "needs at least 2 campaigns, high fidelity first");
  std::vector<TrainingData> data;
  for (const auto& c : campaigns) data.push_back(load_training_data(db_file, c, metric, 2));
  for (std::size_t k = 1; k < K; ++k)
    if (data[k].inputs != data[0].inputs)
      throw InputError(db_file, "--levels", "campaigns '" + data[0].campaign + "' and '" + data[k].campaign +
                                                "' have different parameters; the levels must share their inputs");
  // Nested sets from the lowest level up: a point stays in level k only if level k + 1 has it too.
  using Point = std::vector<double>;
  std::vector<std::map<Point, double>> at(K);
  MfmcSamples s;
  s.names = campaigns;
  s.dropped.assign(K, 0);
  for (std::size_t i = 0; i < data[K - 1].x.size(); ++i) at[K - 1][data[K - 1].x[i]] = data[K - 1].y[i];
  for (std::size_t k = K - 1; k-- > 0;)
    for (std::size_t i = 0; i < data[k].x.size(); ++i) {
      if (at[k + 1].count(data[k].x[i]))
        at[k][data[k].x[i]] = data[k].y[i];
      else
        ++s.dropped[k];
    }
  if (at[0].size() < 2)
    throw InputError(db_file, "--levels",
                     std::to_string(at[0].size()) + " point(s) finished at every level; the estimate needs at "
                     "least 2 (give the levels nested designs, e.g. Monte Carlo of one seed, the higher smaller)");
  // Order: level 1's points in its design order, then each level's own extra points in its design order.
  std::vector<Point> order;
  std::set<Point> seen;
  s.y.resize(K);
  for (std::size_t k = 0; k < K; ++k) {
    for (std::size_t i = 0; i < data[k].x.size(); ++i)
      if (at[k].count(data[k].x[i]) && seen.insert(data[k].x[i]).second) order.push_back(data[k].x[i]);
    for (std::size_t j = 0; j < at[k].size(); ++j) s.y[k].push_back(at[k].at(order[j]));
  }
  store::CampaignStore db(db_file, /*read_only=*/true);
  for (std::size_t k = 0; k < K; ++k) {
    const double given = k < cost_s.size() ? cost_s[k] : 0.0;
    s.cost_s.push_back(given > 0 ? given : db.summary(data[k].campaign_id).mean_wall_s);
    if (!(s.cost_s[k] > 0))
      throw InputError(db_file, "--cost", "campaign '" + campaigns[k] + "' records no wall time; give --cost (s)");
  }
  return s;
}

}  // namespace flume::surrogate
