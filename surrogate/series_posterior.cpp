#include "surrogate/series_posterior.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/errors.h"
#include "surrogate/ot_models.h"
#include "surrogate/posterior_chain.h"

namespace flume::surrogate {

namespace {

// log pi(u) = -1/2 sum_k r_k(u)^2 w_k, r(u) = mu + Phi z(u), w_k = 1 / (sigma^2 + s_k^2).
class SeriesLogPdf : public OT::EvaluationImplementation {
 public:
  SeriesLogPdf(std::vector<OT::Function> scores, Eigen::VectorXd mean, Eigen::MatrixXd basis,
               Eigen::VectorXd weight)
      : scores_(std::move(scores)),
        mean_(std::move(mean)),
        basis_(std::move(basis)),
        weight_(std::move(weight)) {}
  SeriesLogPdf* clone() const override { return new SeriesLogPdf(*this); }
  OT::UnsignedInteger getInputDimension() const override { return scores_.front().getInputDimension(); }
  OT::UnsignedInteger getOutputDimension() const override { return 1; }
  OT::Point operator()(const OT::Point& u) const override {
    Eigen::VectorXd z(scores_.size());
    for (std::size_t c = 0; c < scores_.size(); ++c) z[c] = scores_[c](u)[0];
    const Eigen::VectorXd r = mean_ + basis_ * z;
    return OT::Point(1, -0.5 * r.cwiseAbs2().dot(weight_));
  }

 private:
  std::vector<OT::Function> scores_;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd basis_;  // m x K
  Eigen::VectorXd weight_;
};

OT::Sample column(const Eigen::VectorXd& v) {
  OT::Sample s(v.size(), 1);
  for (Eigen::Index i = 0; i < v.size(); ++i) s(i, 0) = v[i];
  return s;
}

}  // namespace

Posterior series_posterior(const SeriesData& d, const PosteriorSettings& s) {
  const std::size_t p = d.names.size(), n_all = d.points.size();
  Posterior out;
  out.evaluations = n_all;
  if (n_all == 0 || d.residuals.size() != n_all)
    throw InputError("calibration", "evaluations", "none to emulate");
  const std::size_t m = d.residuals[0].size();
  std::vector<double> ssr(n_all);
  for (std::size_t i = 0; i < n_all; ++i)
    ssr[i] = std::inner_product(d.residuals[i].begin(), d.residuals[i].end(), d.residuals[i].begin(), 0.0);
  const std::size_t best = static_cast<std::size_t>(std::min_element(ssr.begin(), ssr.end()) - ssr.begin());
  // The neighbourhood: by the RMS difference of each evaluation's record from the best's (the target and its
  // noise cancel), within `neighbourhood` noises (series_posterior.h).
  std::vector<double> dist(n_all);
  for (std::size_t i = 0; i < n_all; ++i) {
    double s2 = 0;
    for (std::size_t k = 0; k < m; ++k) s2 += std::pow(d.residuals[i][k] - d.residuals[best][k], 2);
    dist[i] = std::sqrt(s2 / static_cast<double>(m));
  }
  std::vector<std::size_t> order(n_all);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return dist[a] < dist[b]; });
  std::size_t n = 0;
  while (n < n_all && (dist[order[n]] <= s.neighbourhood * s.noise_m || n < posterior_min_evaluations(p)))
    ++n;
  if (n < posterior_min_evaluations(p))
    throw InputError("calibration", "evaluations",
                     std::to_string(n_all) + " distinct evaluations; the series emulator needs at least " +
                         std::to_string(posterior_min_evaluations(p)) +
                         " (run the calibration with its profile)");
  out.local = n;
  out.best_rms = std::sqrt(ssr[best] / (d.n_residuals > 0 ? d.n_residuals : static_cast<double>(m)));
  try {
    OT::Sample u(n, p);
    Eigen::MatrixXd r(n, m);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < p; ++j)
        u(i, j) = (d.points[order[i]][j] - d.lower[j]) / (d.upper[j] - d.lower[j]);
      for (std::size_t k = 0; k < m; ++k) r(i, k) = d.residuals[order[i]][k];
    }
    const Eigen::VectorXd mean = r.colwise().mean().transpose();
    const Eigen::MatrixXd centred = r.rowwise() - mean.transpose();
    const Eigen::BDCSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinV);
    const Eigen::VectorXd sv2 = svd.singularValues().cwiseAbs2();
    const double total = sv2.sum();
    std::size_t kept = 1;
    for (double acc = sv2[0]; kept < static_cast<std::size_t>(sv2.size()) && acc < kSeriesVariance * total;
         ++kept)
      acc += sv2[kept];
    out.components = kept;
    const Eigen::MatrixXd basis = svd.matrixV().leftCols(kept);  // m x K, orthonormal columns
    const Eigen::MatrixXd z = centred * basis;                   // n x K scores
    std::vector<OT::KrigingResult> fits;
    std::vector<OT::Function> scores;
    for (std::size_t c = 0; c < kept; ++c) {
      fits.push_back(detail::fit_kriging_linear_trend(u, column(z.col(c))));
      scores.push_back(fits.back().getMetaModel());
    }
    // Leave-one-out error of the emulated series: the emulator rebuilt without the point (its mean, principal
    // directions and scores), only each kriging's covariance parameters kept, so that a series the others'
    // directions do not span counts in full.
    Eigen::MatrixXd e(n, m);
    for (std::size_t i = 0; i < n; ++i) {
      OT::Indices rest;
      Eigen::MatrixXd r_rest(n - 1, m);
      for (std::size_t j = 0, row = 0; j < n; ++j)
        if (j != i) {
          rest.add(j);
          r_rest.row(row++) = r.row(j);
        }
      const Eigen::VectorXd mean_i = r_rest.colwise().mean().transpose();
      const Eigen::MatrixXd centred_i = r_rest.rowwise() - mean_i.transpose();
      const Eigen::BDCSVD<Eigen::MatrixXd> svd_i(centred_i, Eigen::ComputeThinV);
      const std::size_t kept_i =
          std::min<std::size_t>(kept, static_cast<std::size_t>(svd_i.matrixV().cols()));
      const Eigen::MatrixXd basis_i = svd_i.matrixV().leftCols(kept_i);
      const Eigen::MatrixXd z_i = centred_i * basis_i;
      Eigen::VectorXd zi(kept_i);
      for (std::size_t c = 0; c < kept_i; ++c)
        zi[c] = detail::refit_kriging(fits[c], u.select(rest), column(z_i.col(c))).getMetaModel()(u[i])[0];
      e.row(i) = r.row(i) - (mean_i + basis_i * zi).transpose();
    }
    out.q2 = total > 0 ? 1 - e.squaredNorm() / total : std::nan("");
    out.emulator_rms = std::sqrt(e.squaredNorm() / static_cast<double>(n * m));
    // Per sample: the errors of the few left-out series are too few (n of them, m samples) to estimate how
    // the emulator's errors co-vary across samples; their covariance, of rank n, would claim no error
    // outside the directions they happen to span (docs/surrogates.md, the pulse test).
    const Eigen::VectorXd s2 = e.cwiseAbs2().colwise().mean().transpose();
    const Eigen::VectorXd weight =
        (s.noise_m * s.noise_m + (s.emulator_error ? 1.0 : 0.0) * s2.array()).inverse().matrix();
    const OT::Function log_pdf(SeriesLogPdf(scores, mean, basis, weight));
    detail::sample_posterior(log_pdf, u, d, d.points[order[0]], s, out);
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
  return out;
}

}  // namespace flume::surrogate
