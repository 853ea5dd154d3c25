// Calibration posterior on an emulator of the gauge series (after Higdon et al. 2008), the default of
// `flume surrogate posterior`: rather than the misfit, a sharp bowl near its minimum that a few points fit
// badly, it emulates the residual series r = sim - target itself, which near the best varies to first order
// linearly with the parameters.
//   neighbourhood  the evaluations whose records differ from the best's by at most the noise, in RMS over the
//                  samples (D_i = |r_i - r_best| / sqrt(m) <= sigma; at least posterior_min_evaluations, the
//                  nearest): the log-likelihood there is lower by up to about m D^2 / (2 sigma^2), m / 2,
//                  far past any credible region (a few units), so these points surround it; farther, the wave
//                  has moved by more than the noise can tell, where the emulator is not meant to reach
//   emulator       r(u) = mu + sum_c phi_c z_c(u): the neighbourhood's mean record, its principal directions
//                  (SVD) carrying 99.9 % of the variance, each score z_c a kriging with a linear trend over
//                  the parameters scaled to the unit box of the bounds
//   error          s_k^2 = mean over the neighbourhood of e_ik^2, e_i = r_i - r_(-i)(u_i), the leave-one-out
//                  error of the whole emulator (rebuilt without point i) at sample k
//   likelihood     log pi(u) = -1/2 sum_k r_k(u)^2 / (sigma^2 + s_k^2) + const, uniform prior on the bounds
// so the emulator's own error widens the posterior where it is imperfect, sample by sample.
#pragma once
#include "surrogate/posterior.h"
#include "surrogate/series_data.h"

namespace flume::surrogate {

inline constexpr double kSeriesVariance = 0.999;  // share of the series' variance the kept components carry

Posterior series_posterior(const SeriesData& data, const PosteriorSettings& settings);

}  // namespace flume::surrogate
