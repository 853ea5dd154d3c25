// Internal to flume_surrogate: the MCMC both calibration posteriors share (posterior.h). Given a
// log-density over the unit box of the bounds and the evaluations the surrogate rests on, it samples the
// posterior and summarises it into `out` (parameters, acceptance, draws).
#pragma once
#include <openturns/OT.hxx>

#include "surrogate/posterior.h"

namespace flume::surrogate::detail {

// `u`: the surrogate's evaluations in unit coordinates, the best first (the chain starts there); `best`: its
// parameter values. The chain stays in the box `u` spans widened by that span on every side (beyond, a
// surrogate fitted to a few points extrapolates: a quadratic may turn down and draw the chain to a corner).
void sample_posterior(const OT::Function& log_pdf, const OT::Sample& u, const CalibrationBox& box,
                      const std::vector<double>& best, const PosteriorSettings& s, Posterior& out);

}  // namespace flume::surrogate::detail
