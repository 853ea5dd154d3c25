#include "report/sensitivity.h"

#include <algorithm>
#include <cmath>
#include <openturns/OT.hxx>
#include <random>
#include <stdexcept>

namespace flume::report {
namespace {

Interval percentile(std::vector<double> reps, double confidence) {
  OT::Sample s(reps.size(), 1);
  for (std::size_t i = 0; i < reps.size(); ++i) s(i, 0) = reps[i];
  const double a = (1 - confidence) / 2;
  return {s.computeQuantilePerComponent(a)[0], s.computeQuantilePerComponent(1 - a)[0]};
}

// OpenTURNS errors on one line, as the report's own.
[[noreturn]] void rethrow(const OT::Exception& e) {
  std::string what = e.what();
  if (what.rfind("Error: ", 0) == 0) what = what.substr(7);
  std::replace(what.begin(), what.end(), '\n', ' ');
  throw std::invalid_argument(what);
}

}  // namespace

SobolResult sobol_indices(const std::vector<std::vector<double>>& inputs, const std::vector<double>& output,
                          std::size_t base_size, const StatsOptions& opt) {
  if (inputs.empty() || inputs.size() != output.size())
    throw std::invalid_argument("sobol: inputs and output differ in size");
  const std::size_t d = inputs[0].size(), n = base_size;
  if (n == 0 || inputs.size() != n * (d + 2))
    throw std::invalid_argument("sobol: the design has " + std::to_string(inputs.size()) +
                                " rows, not N (d + 2) = " + std::to_string(n * (d + 2)));
  // Pick-freeze needs every matrix's row i: a failure anywhere in block row i removes it everywhere.
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < n; ++i) {
    bool complete = true;
    for (std::size_t b = 0; b < d + 2 && complete; ++b) complete = std::isfinite(output[b * n + i]);
    if (complete) keep.push_back(i);
  }
  SobolResult r;
  r.base_size = keep.size();
  r.base_dropped = n - keep.size();
  if (keep.size() < 4) throw std::invalid_argument("sobol: fewer than 4 complete base rows");
  const std::size_t m = keep.size();
  OT::Sample x(m * (d + 2), d), y(m * (d + 2), 1);
  for (std::size_t b = 0; b < d + 2; ++b)
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t src = b * n + keep[k], dst = b * m + k;
      for (std::size_t j = 0; j < d; ++j) x(dst, j) = inputs[src][j];
      y(dst, 0) = output[src];
    }
  try {
    OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(opt.seed));
    OT::MartinezSensitivityAlgorithm alg(x, y, m);
    alg.setUseAsymptoticDistribution(false);
    alg.setBootstrapSize(std::max<std::size_t>(opt.bootstrap, 2));
    alg.setConfidenceLevel(opt.confidence);
    const OT::Point s1 = alg.getFirstOrderIndices(), st = alg.getTotalOrderIndices();
    const OT::Interval c1 = alg.getFirstOrderIndicesInterval(), ct = alg.getTotalOrderIndicesInterval();
    for (std::size_t j = 0; j < d; ++j) {
      r.first.push_back({s1[j], {c1.getLowerBound()[j], c1.getUpperBound()[j]}});
      r.total.push_back({st[j], {ct.getLowerBound()[j], ct.getUpperBound()[j]}});
    }
  } catch (const OT::Exception& e) {
    rethrow(e);
  }
  return r;
}

CorrelationResult rank_correlations(const std::vector<std::vector<double>>& inputs,
                                    const std::vector<double>& output, const StatsOptions& opt) {
  CorrelationResult r;
  if (inputs.empty()) return r;
  const std::size_t d = inputs[0].size();
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < inputs.size(); ++i)
    if (std::isfinite(output[i])) rows.push_back(i);
  r.n = rows.size();
  const double nan = std::nan("");
  r.spearman.assign(d, {nan, {nan, nan}});
  r.prcc.assign(d, {nan, {nan, nan}});
  // Inputs that vary over the rows; a constant column has no correlation and makes PRCC singular.
  std::vector<std::size_t> cols;
  for (std::size_t j = 0; j < d; ++j) {
    bool varies = false;
    for (std::size_t i : rows) varies = varies || inputs[i][j] != inputs[rows[0]][j];
    if (varies) cols.push_back(j);
  }
  if (cols.empty() || rows.size() < cols.size() + 3) return r;
  const std::size_t dc = cols.size();
  auto samples = [&](const std::vector<std::size_t>& pick, OT::Sample& x, OT::Sample& y) {
    x = OT::Sample(pick.size(), dc);
    y = OT::Sample(pick.size(), 1);
    for (std::size_t k = 0; k < pick.size(); ++k) {
      for (std::size_t c = 0; c < dc; ++c) x(k, c) = inputs[pick[k]][cols[c]];
      y(k, 0) = output[pick[k]];
    }
  };
  try {
    OT::Sample x, y;
    samples(rows, x, y);
    const OT::CorrelationAnalysis ca(x, y);
    const OT::Point sp = ca.computeSpearmanCorrelation(), pr = ca.computePRCC();
    std::vector<std::vector<double>> sp_reps(dc), pr_reps(dc);
    std::mt19937_64 rng(opt.seed + 11);
    std::uniform_int_distribution<std::size_t> pick(0, rows.size() - 1);
    std::vector<std::size_t> star(rows.size());
    for (std::size_t b = 0; b < opt.bootstrap; ++b) {
      for (auto& i : star) i = rows[pick(rng)];
      samples(star, x, y);
      OT::Point spb, prb;
      try {
        const OT::CorrelationAnalysis cb(x, y);
        spb = cb.computeSpearmanCorrelation();
        prb = cb.computePRCC();
      } catch (const OT::Exception&) {
        continue;  // a degenerate resample (ties everywhere) carries no information; it is skipped
      }
      for (std::size_t c = 0; c < dc; ++c) {
        if (std::isfinite(spb[c])) sp_reps[c].push_back(spb[c]);
        if (std::isfinite(prb[c])) pr_reps[c].push_back(prb[c]);
      }
    }
    for (std::size_t c = 0; c < dc; ++c) {
      r.spearman[cols[c]] = {
          sp[c], sp_reps[c].size() > 1 ? percentile(sp_reps[c], opt.confidence) : Interval{nan, nan}};
      r.prcc[cols[c]] = {pr[c],
                         pr_reps[c].size() > 1 ? percentile(pr_reps[c], opt.confidence) : Interval{nan, nan}};
    }
  } catch (const OT::Exception& e) {
    rethrow(e);
  }
  return r;
}

}  // namespace flume::report
