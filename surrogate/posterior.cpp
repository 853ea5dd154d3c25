#include "surrogate/posterior.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "common/errors.h"
#include "store/db/campaign_store.h"
#include "surrogate/ot_models.h"
#include "surrogate/posterior_chain.h"

namespace flume::surrogate {

namespace {

// The neighbourhood of the best evaluation the surrogate is fitted to: a log-likelihood drop of 50 is far
// beyond any credible region (3 for a 95 % region of two parameters).
constexpr double kLocalLogLikelihood = 50;

}  // namespace

Posterior misfit_posterior(const MisfitData& d, const PosteriorSettings& s) {
  const std::size_t p = d.names.size(), n_all = d.ssr.size();
  Posterior out;
  out.evaluations = n_all;
  try {
    std::vector<std::size_t> order(n_all);
    for (std::size_t i = 0; i < n_all; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return d.ssr[a] < d.ssr[b]; });
    const double cut = d.ssr[order[0]] + kLocalLogLikelihood * 2 * s.noise_m * s.noise_m;
    std::size_t n = 0;
    while (n < n_all && (d.ssr[order[n]] <= cut || n < posterior_min_evaluations(p))) ++n;
    if (n < posterior_min_evaluations(p))
      throw InputError("calibration", "evaluations",
                       std::to_string(n_all) + " distinct evaluations; the misfit surrogate needs at least " +
                           std::to_string(posterior_min_evaluations(p)) + " (run the calibration with its profile)");
    out.local = n;
    out.best_rms = std::sqrt(d.ssr[order[0]] / std::max(d.n_residuals, 1.0));
    OT::Sample u(n, p), y(n, 1);
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < p; ++j)
        u(i, j) = (d.points[order[i]][j] - d.lower[j]) / (d.upper[j] - d.lower[j]);
      y(i, 0) = d.ssr[order[i]];
    }
    const OT::KrigingResult k = detail::fit_kriging_quadratic_trend(u, y);
    {
      // Leave-one-out check of the misfit surrogate (the covariance and trend basis kept).
      double mean = y.computeMean()[0], sse = 0, sst = 0;
      for (std::size_t i = 0; i < n; ++i) {
        OT::Indices rest;
        for (std::size_t j = 0; j < n; ++j)
          if (j != i) rest.add(j);
        const double yp = detail::refit_kriging(k, u.select(rest), y.select(rest)).getMetaModel()(u[i])[0];
        sse += std::pow(yp - y(i, 0), 2);
        sst += std::pow(y(i, 0) - mean, 2);
      }
      out.q2 = sst > 0 ? 1 - sse / sst : std::nan("");
    }
    // log pi(u) = -SSR(u) / (2 sigma^2), uniform prior, on the part of the unit box the surrogate knows.
    const OT::Function::FunctionCollection terms(1, k.getMetaModel());
    const OT::LinearCombinationFunction log_pdf(terms, OT::Point(1, -0.5 / (s.noise_m * s.noise_m)));
    detail::sample_posterior(log_pdf, u, d, d.points[order[0]], s, out);
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
  return out;
}

double noise_alone_rms_ratio(double n_residuals, double level) {
  const double n = std::max(1.0, std::round(n_residuals));
  try {
    return std::sqrt(OT::ChiSquare(n).computeQuantile(level)[0] / n);
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
}

MisfitData load_calibration_misfit(const std::string& db_file, const std::string& name, int rounds_before) {
  using json = nlohmann::json;
  store::CampaignStore db(db_file, /*read_only=*/true);
  const auto c = db.find_campaign(name);
  if (!c) throw InputError(db_file, "--calibration", "no calibration named '" + name + "'");
  MisfitData d;
  d.spec_json = c->spec;
  const json spec = json::parse(c->spec);
  if (!spec.contains("parameters") || !spec.contains("objective"))
    throw InputError(db_file, "--calibration", "'" + name + "' is a campaign, not a calibration");
  for (const auto& p : spec["parameters"]) {
    d.names.push_back(p.at("path").get<std::string>());
    d.lower.push_back(p.at("lower").get<double>());
    d.upper.push_back(p.at("upper").get<double>());
  }
  if (spec["objective"].contains("time_shift")) {
    d.names.push_back("objective.time_shift_s");
    d.lower.push_back(spec["objective"]["time_shift"].at("lower").get<double>());
    d.upper.push_back(spec["objective"]["time_shift"].at("upper").get<double>());
  }
  std::map<std::vector<double>, double> unique;  // a point evaluated twice (replayed) counts once
  for (const auto& e : db.evaluations(c->id)) {
    if (e.phase == kRefinePhase && e.start >= rounds_before) continue;
    const json params = json::parse(e.params_json), terms = json::parse(e.terms_json);
    if (terms.contains("failed") || !terms.contains("rms_m") || !terms["rms_m"].is_number()) continue;
    double n = 0;
    for (const auto& [g, t] : terms["gauges"].items()) n += t.value("samples", 0.0);
    std::vector<double> x;
    for (const auto& name_j : d.names) x.push_back(params.value(name_j, 0.0));
    const double rms = terms["rms_m"].get<double>();
    unique[x] = rms * rms * n;
    d.n_residuals = n;
  }
  for (const auto& [x, ssr] : unique) {
    d.points.push_back(x);
    d.ssr.push_back(ssr);
  }
  if (d.points.size() < posterior_min_evaluations(d.names.size()))
    throw InputError(db_file, "--calibration",
                     "'" + name + "' has " + std::to_string(d.points.size()) +
                         " distinct evaluations; the misfit surrogate needs at least " +
                         std::to_string(posterior_min_evaluations(d.names.size())) +
                         " (run the calibration with its profile)");
  return d;
}

std::string predictive_spec(const CalibrationBox& d, const Posterior& post, const std::string& calibration,
                            double end_time_s) {
  using json = nlohmann::json;
  const json spec = json::parse(d.spec_json);
  if (!spec.contains("scene"))
    throw InputError("command line", "--draws", "calibration '" + calibration + "' runs a stand-in model, not a scene");
  const std::filesystem::path scene = spec["scene"].get<std::string>();
  if (!std::filesystem::exists(scene))
    throw InputError(scene.string(), "scene", "missing: the calibration's scene file is no longer there");
  json overrides = spec.value("overrides", json::object());
  overrides["solver.end_time"] = end_time_s;
  json points = json::array();
  json optimum = {{"label", "optimum"}};  // the best evaluation, run over the same time as the draws
  for (const auto& p : post.parameters)
    if (p.name != "objective.time_shift_s") optimum[p.name] = p.best;
  points.push_back(optimum);
  for (std::size_t i = 0; i < post.draws.size(); ++i) {
    char label[32];
    std::snprintf(label, sizeof label, "draw-%03zu", i + 1);
    json point = {{"label", label}};
    for (std::size_t j = 0; j < d.names.size(); ++j)
      if (d.names[j] != "objective.time_shift_s") point[d.names[j]] = post.draws[i][j];
    points.push_back(point);
  }
  return json{{"name", calibration + "-predictive"},
              {"description", "posterior draws of calibration '" + calibration +
                                  "' (flume surrogate posterior --draws): their runs' spread is the predictive band"},
              {"scene", std::filesystem::absolute(scene).lexically_normal().string()},
              {"overrides", overrides},
              {"design", {{"type", "list"}, {"points", points}}}}
      .dump(2);
}

}  // namespace flume::surrogate
