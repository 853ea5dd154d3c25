#include "surrogate/classifier.h"

#include <cmath>

#include "surrogate/ot_models.h"

namespace flume::surrogate {
namespace {

constexpr std::size_t kMaxLeaveOneOut = 200;

std::size_t count_right(const OT::Sample& predicted, const std::vector<double>& label) {
  std::size_t right = 0;
  for (std::size_t i = 0; i < label.size(); ++i) right += (predicted(i, 0) > 0.5) == (label[i] > 0.5);
  return right;
}

}  // namespace

ClassifierQuality classify_inside(const std::vector<std::vector<double>>& inside,
                                  const std::vector<std::vector<double>>& outside,
                                  const std::vector<std::vector<double>>& holdout_inside,
                                  const std::vector<std::vector<double>>& holdout_outside,
                                  const OT::Distribution& joint, std::size_t mc_size, std::uint64_t seed) {
  ClassifierQuality q;
  q.inside = inside.size();
  q.outside = outside.size();
  std::vector<std::vector<double>> x = inside;
  x.insert(x.end(), outside.begin(), outside.end());
  std::vector<double> label(inside.size(), 1.0);
  label.resize(x.size(), 0.0);
  const OT::Sample xs = detail::to_sample(x), ys = detail::to_column(label);
  const OT::KrigingResult fitted = detail::fit_kriging(xs, ys);

  // Every run judged by a classifier that never saw it (the fitted covariance kept): leave-one-out, or for
  // many runs 20 folds of every 20th run (a refit costs n^3, and interleaved folds hold both classes).
  const std::size_t n = x.size(), folds = n <= kMaxLeaveOneOut ? n : 20;
  std::size_t right = 0;
  for (std::size_t f = 0; f < folds; ++f) {
    OT::Indices rest, test;
    for (std::size_t j = 0; j < n; ++j) (j % folds == f ? test : rest).add(j);
    const OT::Function model = detail::refit_kriging(fitted, xs.select(rest), ys.select(rest)).getMetaModel();
    const OT::Sample predicted = model(xs.select(test));
    for (std::size_t i = 0; i < test.getSize(); ++i) right += (predicted(i, 0) > 0.5) == (label[test[i]] > 0.5);
  }
  q.accuracy_cv = static_cast<double>(right) / static_cast<double>(n);

  const OT::Function classifier = fitted.getMetaModel();
  q.holdout_inside = holdout_inside.size();
  q.holdout_outside = holdout_outside.size();
  q.accuracy_holdout = std::nan("");
  if (!holdout_inside.empty() || !holdout_outside.empty()) {
    std::vector<std::vector<double>> xh = holdout_inside;
    xh.insert(xh.end(), holdout_outside.begin(), holdout_outside.end());
    std::vector<double> lh(holdout_inside.size(), 1.0);
    lh.resize(xh.size(), 0.0);
    q.accuracy_holdout =
        static_cast<double>(count_right(classifier(detail::to_sample(xh)), lh)) / static_cast<double>(xh.size());
  }
  OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(seed + 404));
  const OT::Sample judged = classifier(joint.getSample(mc_size));
  std::size_t inside_count = 0;
  for (OT::UnsignedInteger i = 0; i < judged.getSize(); ++i) inside_count += judged(i, 0) > 0.5;
  q.p_inside = static_cast<double>(inside_count) / static_cast<double>(judged.getSize());
  return q;
}

}  // namespace flume::surrogate
