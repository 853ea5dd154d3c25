#include "surrogate/fit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "campaigns/spec.h"
#include "common/errors.h"
#include "sampling/ot_bridge.h"
#include "surrogate/classifier.h"
#include "surrogate/ot_models.h"

namespace flume::surrogate {
namespace {

using json = nlohmann::json;
using detail::from_column;
using detail::to_column;
using detail::to_sample;

OT::Interval percentile(const std::vector<double>& reps, double confidence) {
  const double a = (1 - confidence) / 2;
  const OT::Sample s = to_column(reps);
  return OT::Interval(s.computeQuantilePerComponent(a), s.computeQuantilePerComponent(1 - a));
}

double q2(const std::vector<double>& observed, const std::vector<double>& predicted) {
  double mean = 0, sse = 0, sst = 0;
  for (double v : observed) mean += v / observed.size();
  for (std::size_t i = 0; i < observed.size(); ++i) {
    sse += (observed[i] - predicted[i]) * (observed[i] - predicted[i]);
    sst += (observed[i] - mean) * (observed[i] - mean);
  }
  return sst > 0 ? 1.0 - sse / sst : std::nan("");
}

double exceed_fraction(const OT::Sample& y, double t) {
  std::size_t above = 0;
  for (OT::UnsignedInteger i = 0; i < y.getSize(); ++i) above += y(i, 0) > t;
  return static_cast<double>(above) / static_cast<double>(y.getSize());
}

json estimate_json(const Estimate& e) { return {{"value", e.value}, {"lo", e.lo}, {"hi", e.hi}}; }

// Out-of-fold predictions of a k-fold split (OT::KFoldSplitter, contiguous folds of the design order).
template <typename Refit>
std::vector<double> out_of_fold(const OT::Sample& x, const OT::Sample& y, std::size_t k, Refit refit) {
  const std::size_t n = x.getSize();
  std::vector<double> predicted(n, std::nan(""));
  OT::KFoldSplitter splitter(n, k);
  for (std::size_t f = 0; f < k; ++f) {
    OT::Indices test;
    const OT::Indices train = splitter.generate(test);
    const OT::Function model = refit(x.select(train), y.select(train));
    const OT::Sample yp = model(x.select(test));
    for (std::size_t i = 0; i < test.getSize(); ++i) predicted[test[i]] = yp(i, 0);
  }
  return predicted;
}

ExceedanceCurve exceedance_curve(const OT::Function& model, const OT::Distribution& joint, const FitSettings& s,
                                 const std::vector<OT::Function>& replicates) {
  ExceedanceCurve c;
  c.mc_size = s.mc_size;
  OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(s.seed + 101));
  const OT::Sample y = model(joint.getSample(s.mc_size));
  c.thresholds = s.thresholds;
  if (c.thresholds.empty()) {
    const double lo = y.computeQuantilePerComponent(0.02)[0], hi = y.computeQuantilePerComponent(0.995)[0];
    for (int i = 0; i < 25; ++i) c.thresholds.push_back(lo + (hi - lo) * i / 24.0);
  }
  for (double t : c.thresholds) c.p.push_back(exceed_fraction(y, t));
  std::vector<std::vector<double>> reps(c.thresholds.size());
  const std::size_t m = std::max<std::size_t>(s.mc_size / 10, 100);
  for (const auto& f : replicates) {
    const OT::Sample yr = f(joint.getSample(m));
    for (std::size_t i = 0; i < c.thresholds.size(); ++i) reps[i].push_back(exceed_fraction(yr, c.thresholds[i]));
  }
  c.replicates = replicates.size();
  if (!replicates.empty()) c.band_points = m;
  for (std::size_t i = 0; i < c.thresholds.size(); ++i) {
    if (reps[i].size() < 2) {
      c.lo.push_back(std::nan(""));
      c.hi.push_back(std::nan(""));
      continue;
    }
    const OT::Interval iv = percentile(reps[i], s.confidence);
    c.lo.push_back(iv.getLowerBound()[0]);
    c.hi.push_back(iv.getUpperBound()[0]);
  }
  return c;
}

// Conditional realisations of the kriging process at a Monte Carlo sample of the inputs: each gives one
// exceedance curve, their spread the curve's band (the surrogate's uncertainty, on one input sample).
ExceedanceCurve kriging_exceedance(const OT::KrigingResult& k, const OT::Distribution& joint, const FitSettings& s) {
  ExceedanceCurve c = exceedance_curve(k.getMetaModel(), joint, s, {});
  const std::size_t m = std::min<std::size_t>(std::max<std::size_t>(s.mc_size / 20, 100), 1000);
  const std::size_t count = std::min<std::size_t>(s.bootstrap, 200);
  if (count < 2) return c;
  try {
    OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(s.seed + 202));
    const OT::Sample at = joint.getSample(m);
    const OT::KrigingRandomVector process(k, at);
    const OT::Sample realisations = process.getSample(count);  // count x m
    std::vector<std::vector<double>> reps(c.thresholds.size());
    for (std::size_t r = 0; r < count; ++r) {
      OT::Sample yr(m, 1);
      for (std::size_t i = 0; i < m; ++i) yr(i, 0) = realisations(r, i);
      for (std::size_t i = 0; i < c.thresholds.size(); ++i) reps[i].push_back(exceed_fraction(yr, c.thresholds[i]));
    }
    for (std::size_t i = 0; i < c.thresholds.size(); ++i) {
      const OT::Interval iv = percentile(reps[i], s.confidence);
      c.lo[i] = iv.getLowerBound()[0];
      c.hi[i] = iv.getUpperBound()[0];
    }
    c.replicates = count;
    c.band_points = m;
  } catch (const OT::Exception&) {
    // A conditional covariance too close to singular (runs nearly repeated): the curve keeps no band.
  }
  return c;
}

}  // namespace

const char* to_string(Kind k) { return k == Kind::kChaos ? "chaos" : "kriging"; }

std::optional<Kind> kind_from(const std::string& s) {
  if (s == "chaos") return Kind::kChaos;
  if (s == "kriging") return Kind::kKriging;
  return std::nullopt;
}

FitResult fit_surrogate(const TrainingData& data, const FitSettings& s) {
  const std::size_t n_all = data.y.size(), d = data.inputs.size();
  if (s.holdout + 4 > n_all)
    throw InputError(data.db_file, "--holdout",
                     "must leave at least 4 runs to fit (" + std::to_string(n_all) + " runs, holdout " +
                         std::to_string(s.holdout) + ")");
  FitResult r;
  r.kind = s.kind;
  const std::size_t n = n_all - s.holdout;
  r.train_runs.assign(data.run_ids.begin(), data.run_ids.begin() + static_cast<long>(n));
  r.holdout_runs.assign(data.run_ids.begin() + static_cast<long>(n), data.run_ids.end());
  std::vector<std::vector<double>> xt(data.x.begin(), data.x.begin() + static_cast<long>(n));
  std::vector<double> yt(data.y.begin(), data.y.begin() + static_cast<long>(n));
  r.holdout_observed.assign(data.y.begin() + static_cast<long>(n), data.y.end());
  try {
    const OT::Distribution joint = sampling::detail::make_ot_joint(data.distributions, data.correlations);
    const OT::Sample x = to_sample(xt), y = to_column(yt);
    r.folds = (s.folds == 0 || s.folds >= n) ? n : std::max<std::size_t>(s.folds, 2);
    OT::Function metamodel;
    std::vector<OT::Function> replicate_models;
    if (s.kind == Kind::kChaos) {
      r.degree = s.degree > 0 ? s.degree : detail::default_degree(d, n);
      const OT::FunctionalChaosResult chaos = detail::fit_chaos(x, y, joint, r.degree);
      metamodel = chaos.getMetaModel();
      r.terms = chaos.getIndices().getSize();
      r.cv_predicted = out_of_fold(x, y, r.folds, [&](const OT::Sample& xf, const OT::Sample& yf) {
        return detail::fit_chaos(xf, yf, joint, r.degree).getMetaModel();
      });
      const OT::FunctionalChaosRandomVector vector(chaos);
      r.mean = vector.getMean()[0];
      r.std = std::sqrt(vector.getCovariance()(0, 0));
      const OT::FunctionalChaosSobolIndices sobol(chaos);
      const auto reps = detail::chaos_replicates(chaos, s.bootstrap, s.seed);
      r.sobol_replicates = reps.size();
      std::vector<std::vector<double>> first(d), total(d);
      for (const auto& rep : reps) {
        const OT::FunctionalChaosSobolIndices sb(rep);
        for (std::size_t j = 0; j < d; ++j) {
          first[j].push_back(sb.getSobolIndex(j));
          total[j].push_back(sb.getSobolTotalIndex(j));
        }
        replicate_models.push_back(rep.getMetaModel());
      }
      for (std::size_t j = 0; j < d; ++j) {
        Estimate f{sobol.getSobolIndex(j), std::nan(""), std::nan("")};
        Estimate t{sobol.getSobolTotalIndex(j), std::nan(""), std::nan("")};
        if (reps.size() >= 2) {
          const OT::Interval fi = percentile(first[j], s.confidence), ti = percentile(total[j], s.confidence);
          f.lo = fi.getLowerBound()[0];
          f.hi = fi.getUpperBound()[0];
          t.lo = ti.getLowerBound()[0];
          t.hi = ti.getUpperBound()[0];
        }
        r.first.push_back(f);
        r.total.push_back(t);
      }
      r.exceedance = exceedance_curve(metamodel, joint, s, replicate_models);
      r.model = detail::save_study(chaos);
    } else {
      const OT::KrigingResult kriging = detail::fit_kriging(x, y);
      metamodel = kriging.getMetaModel();
      r.cv_predicted = out_of_fold(x, y, r.folds, [&](const OT::Sample& xf, const OT::Sample& yf) {
        return detail::refit_kriging(kriging, xf, yf).getMetaModel();
      });
      r.exceedance = kriging_exceedance(kriging, joint, s);
      OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(s.seed + 303));
      const OT::Sample ym = metamodel(joint.getSample(s.mc_size));
      r.mean = ym.computeMean()[0];
      r.std = ym.computeStandardDeviation()[0];
      r.model = detail::save_study(kriging);
    }
    r.cv_observed = yt;
    r.q2_cv = q2(yt, r.cv_predicted);
    r.q2_holdout = std::nan("");
    if (s.holdout > 0) {
      const std::vector<std::vector<double>> xh(data.x.begin() + static_cast<long>(n), data.x.end());
      const OT::Sample xs = to_sample(xh), ys = to_column(r.holdout_observed);
      r.holdout_predicted = from_column(metamodel(xs));
      r.q2_holdout = OT::MetaModelValidation(xs, ys, metamodel).computePredictivityFactor()[0];
    }
    const std::size_t outside_train = data.x_outside.size() - data.outside_held_back;
    if (outside_train > 0) {
      const auto split = data.x_outside.begin() + static_cast<long>(outside_train);
      const std::vector<std::vector<double>> xh(data.x.begin() + static_cast<long>(n), data.x.end());
      try {
        r.classifier = classify_inside(xt, {data.x_outside.begin(), split}, xh, {split, data.x_outside.end()}, joint,
                                       s.mc_size, s.seed);
      } catch (const OT::Exception&) {
        // An indicator OpenTURNS cannot fit (runs nearly repeated): the fit stands, without a classifier.
      }
    }
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
  return r;
}

std::string settings_json(const FitSettings& s) {
  json j{{"kind", to_string(s.kind)}, {"degree", s.degree},         {"folds", s.folds},
         {"holdout", s.holdout},      {"validation", s.validation}, {"bootstrap", s.bootstrap},   {"confidence", s.confidence},
         {"mc_size", s.mc_size},      {"thresholds", s.thresholds}, {"seed", s.seed}};
  if (!s.given.empty()) j["given"] = s.given;  // absent otherwise: fits stored before conditions stay current
  return j.dump();
}

std::string runs_json(const FitResult& r) {
  return json{{"train", r.train_runs}, {"holdout", r.holdout_runs}}.dump();
}

std::string quality_json(const FitResult& r, const TrainingData& data, const FitSettings& s) {
  auto finite_or_null = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  auto finite_list = [&](const std::vector<double>& v) {
    json a = json::array();
    for (double x : v) a.push_back(finite_or_null(x));
    return a;
  };
  json q = {{"kind", to_string(r.kind)},
            {"metric", data.metric},
            {"inputs", data.inputs},
            {"n_train", r.train_runs.size()},
            {"n_holdout", r.holdout_runs.size()},
            {"folds", r.folds},
            {"q2_cv", finite_or_null(r.q2_cv)},
            {"q2_holdout", finite_or_null(r.q2_holdout)},
            {"cv", {{"observed", r.cv_observed}, {"predicted", finite_list(r.cv_predicted)}}},
            {"holdout", {{"observed", r.holdout_observed}, {"predicted", finite_list(r.holdout_predicted)}}},
            {"mean", r.mean},
            {"std", r.std},
            {"confidence", s.confidence}};
  if (r.kind == Kind::kChaos) {
    q["degree"] = r.degree;
    q["terms"] = r.terms;
    json first = json::array(), total = json::array();
    for (const auto& e : r.first) first.push_back(estimate_json(e));
    for (const auto& e : r.total) total.push_back(estimate_json(e));
    q["sobol"] = {{"first", first}, {"total", total}, {"replicates", r.sobol_replicates}};
  }
  if (!data.given.empty()) q["given"] = data.given;
  if (r.classifier) {
    const ClassifierQuality& k = *r.classifier;
    q["classifier"] = {{"inside", k.inside},
                       {"outside", k.outside},
                       {"accuracy_cv", k.accuracy_cv},
                       {"holdout_inside", k.holdout_inside},
                       {"holdout_outside", k.holdout_outside},
                       {"accuracy_holdout", finite_or_null(k.accuracy_holdout)},
                       {"p_inside", k.p_inside}};
  }
  const auto& c = r.exceedance;
  q["exceedance"] = {{"thresholds", c.thresholds}, {"p", c.p},           {"lo", finite_list(c.lo)},
                     {"hi", finite_list(c.hi)},    {"mc_size", c.mc_size}, {"replicates", c.replicates},
                     {"band_points", c.band_points}};
  return q.dump();
}

std::string fit_hash(const TrainingData& data, const FitSettings& s) {
  std::string text = settings_json(s) + "|" + data.metric;
  char buf[64];
  for (std::size_t i = 0; i < data.y.size(); ++i) {
    std::snprintf(buf, sizeof buf, "|%lld:%.17g", static_cast<long long>(data.run_ids[i]), data.y[i]);
    text += buf;
  }
  for (const auto& x : data.x_outside)  // the classifier's runs
    for (double v : x) {
      std::snprintf(buf, sizeof buf, "|o%.17g", v);
      text += buf;
    }
  return campaigns::text_hash(text);
}

struct Surrogate::Impl {
  OT::Function model;
  std::optional<OT::KrigingResult> kriging;
};

Surrogate::Surrogate(Kind kind, const std::string& model_xml) : kind_(kind), impl_(std::make_unique<Impl>()) {
  try {
    if (kind == Kind::kChaos) {
      OT::FunctionalChaosResult r;
      detail::load_study(model_xml, r);
      impl_->model = r.getMetaModel();
    } else {
      OT::KrigingResult r;
      detail::load_study(model_xml, r);
      impl_->model = r.getMetaModel();
      impl_->kriging = r;
    }
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
}

Surrogate::~Surrogate() = default;
Surrogate::Surrogate(Surrogate&&) noexcept = default;

std::size_t Surrogate::dimension() const { return impl_->model.getInputDimension(); }

std::vector<double> Surrogate::predict(const std::vector<std::vector<double>>& points) const {
  try {
    return from_column(impl_->model(to_sample(points)));
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
}

std::vector<double> Surrogate::variance(const std::vector<std::vector<double>>& points) const {
  if (!impl_->kriging) return {};
  try {
    return from_column(impl_->kriging->getConditionalMarginalVariance(to_sample(points)));
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
}

}  // namespace flume::surrogate
