#include "surrogate/posterior_chain.h"

#include <algorithm>

namespace flume::surrogate::detail {

void sample_posterior(const OT::Function& log_pdf, const OT::Sample& u, const CalibrationBox& d,
                      const std::vector<double>& best, const PosteriorSettings& s, Posterior& out) {
  const std::size_t p = d.names.size();
  OT::Point lo = u.getMin(), hi = u.getMax(), step(p);
  for (std::size_t j = 0; j < p; ++j) {
    const double span = std::max(hi[j] - lo[j], 1e-6);
    lo[j] = std::max(0.0, lo[j] - span);
    hi[j] = std::min(1.0, hi[j] + span);
    step[j] = 0.02 * (hi[j] - lo[j]);
  }
  OT::Point start = u[0];
  for (std::size_t j = 0; j < p; ++j)
    start[j] = std::clamp(start[j], lo[j] + 1e-9 * (hi[j] - lo[j]), hi[j] - 1e-9 * (hi[j] - lo[j]));
  // Proposal: a step of 2 % of the support, adapted by OpenTURNS towards its target acceptance rate.
  OT::RandomWalkMetropolisHastings sampler(log_pdf, OT::Interval(lo, hi), start,
                                           OT::Normal(OT::Point(p, 0.0), step));
  sampler.setBurnIn(s.burn_in);
  OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(s.seed));
  const OT::Sample chain = sampler.getSample(s.samples);
  out.acceptance = sampler.getAcceptanceRate();
  const std::size_t kept = std::min<std::size_t>(s.draws, chain.getSize());
  out.draws.clear();
  for (std::size_t i = 0; i < kept; ++i) {
    // The middle of each of `kept` equal stretches of the chain: far apart, so nearly independent.
    const OT::Point u_i = chain[(2 * i + 1) * chain.getSize() / (2 * kept)];
    std::vector<double> x;
    for (std::size_t j = 0; j < p; ++j) x.push_back(d.lower[j] + u_i[j] * (d.upper[j] - d.lower[j]));
    out.draws.push_back(std::move(x));
  }
  const double a = (1 - s.confidence) / 2;
  out.parameters.clear();
  for (std::size_t j = 0; j < p; ++j) {
    const OT::Sample m = chain.getMarginal(j);
    auto phys = [&](double v) { return d.lower[j] + v * (d.upper[j] - d.lower[j]); };
    out.parameters.push_back({d.names[j], best[j], phys(m.computeMean()[0]), phys(m.computeMedian()[0]),
                              phys(m.computeQuantile(a)[0]), phys(m.computeQuantile(1 - a)[0])});
    // An interval within 1 % of a support edge that is not a bound of the calibration is cut by the support.
    const double margin = 0.01 * (hi[j] - lo[j]);
    out.parameters.back().cut = (lo[j] > 0 && m.computeQuantile(a)[0] < lo[j] + margin) ||
                                (hi[j] < 1 && m.computeQuantile(1 - a)[0] > hi[j] - margin);
  }
}

}  // namespace flume::surrogate::detail
