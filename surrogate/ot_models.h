// Internal to flume_surrogate: the OpenTURNS side of the surrogates (fit, refit, replicate, save, load).
// Nothing outside surrogate/ includes this header.
#pragma once
#include <openturns/OT.hxx>

#include <cstdint>
#include <string>
#include <vector>

namespace flume::surrogate::detail {

OT::Sample to_sample(const std::vector<std::vector<double>>& rows);
OT::Sample to_column(const std::vector<double>& values);
std::vector<double> from_column(const OT::Sample& s);

// The largest total degree whose full basis has at most `n` terms (LARS then keeps a sparse subset), in
// [1, 12].
int default_degree(std::size_t dimension, std::size_t n);

// Polynomial chaos by least squares with sparse selection: the total-degree basis of the inputs' orthonormal
// polynomials (OpenTURNS' StandardDistributionPolynomialFactory per marginal), LARS path, the model picked
// by corrected leave-one-out (Blatman & Sudret 2011).
OT::FunctionalChaosResult fit_chaos(const OT::Sample& x, const OT::Sample& y, const OT::Distribution& joint,
                                    int degree);

// Bootstrap replicates of a chaos expansion: the runs resampled with replacement and the coefficients of the
// selected terms refitted by least squares (the selection is kept: it is what the interval is conditional
// on). Replicates whose resample leaves the least-squares problem rank deficient are skipped.
std::vector<OT::FunctionalChaosResult> chaos_replicates(const OT::FunctionalChaosResult& fitted, std::size_t count,
                                                        std::uint64_t seed);

// Kriging with a constant trend and a Matern 5/2 covariance, its scales and amplitude by maximum likelihood.
OT::KrigingResult fit_kriging(const OT::Sample& x, const OT::Sample& y);
// The same with a quadratic trend (universal kriging): for a function known to be near a quadratic, such as
// a misfit near its minimum, whose extrapolation should follow the quadratic rather than fall to the mean.
OT::KrigingResult fit_kriging_quadratic_trend(const OT::Sample& x, const OT::Sample& y);
// The same with a linear trend: for a function near a linear one, such as a gauge series near an optimum.
OT::KrigingResult fit_kriging_linear_trend(const OT::Sample& x, const OT::Sample& y);
// The same covariance (scales, amplitude) and trend basis on other runs: cross-validation folds and adaptive
// batches.
OT::KrigingResult refit_kriging(const OT::KrigingResult& fitted, const OT::Sample& x, const OT::Sample& y);

// A result as OpenTURNS' XML study text, and back.
std::string save_study(const OT::PersistentObject& object);
void load_study(const std::string& xml, OT::PersistentObject& object);

// OpenTURNS' warnings off (a command's output is its own lines; the fits' numerical notes are not for users).
void quiet_warnings();

// OpenTURNS' errors on one line.
[[noreturn]] void rethrow(const OT::Exception& e);

}  // namespace flume::surrogate::detail
