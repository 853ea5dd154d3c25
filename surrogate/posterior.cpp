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

namespace flume::surrogate {

Posterior misfit_posterior(const MisfitData& d, const PosteriorSettings& s) {
  const std::size_t p = d.names.size(), n = d.ssr.size();
  Posterior out;
  out.evaluations = n;
  try {
    OT::Sample u(n, p);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < p; ++j) u(i, j) = (d.points[i][j] - d.lower[j]) / (d.upper[j] - d.lower[j]);
    const OT::Sample y = detail::to_column(d.ssr);
    const OT::KrigingResult k = detail::fit_kriging(u, y);
    {
      // Out-of-fold check of the misfit surrogate (5 folds, the covariance kept).
      double mean = y.computeMean()[0], sse = 0, sst = 0;
      OT::KFoldSplitter splitter(n, std::min<std::size_t>(5, n));
      for (std::size_t f = 0; f < std::min<std::size_t>(5, n); ++f) {
        OT::Indices test;
        const OT::Indices train = splitter.generate(test);
        const OT::Sample yp = detail::refit_kriging(k, u.select(train), y.select(train)).getMetaModel()(u.select(test));
        for (std::size_t i = 0; i < test.getSize(); ++i) {
          sse += std::pow(yp(i, 0) - y(test[i], 0), 2);
          sst += std::pow(y(test[i], 0) - mean, 2);
        }
      }
      out.q2 = sst > 0 ? 1 - sse / sst : std::nan("");
    }
    // log pi(u) = -SSR(u) / (2 sigma^2) on the unit box (uniform prior).
    const OT::Function::FunctionCollection terms(1, k.getMetaModel());
    const OT::LinearCombinationFunction log_pdf(terms, OT::Point(1, -0.5 / (s.noise_m * s.noise_m)));
    const std::size_t best = static_cast<std::size_t>(
        std::min_element(d.ssr.begin(), d.ssr.end()) - d.ssr.begin());
    OT::Point start = u[best];
    for (auto& v : start) v = std::clamp(v, 1e-9, 1 - 1e-9);
    // Proposal: a step of 2 % of each range, adapted by OpenTURNS towards its target acceptance rate.
    OT::RandomWalkMetropolisHastings sampler(log_pdf, OT::Interval(p), start,
                                              OT::Normal(OT::Point(p, 0.0), OT::Point(p, 0.02)));
    sampler.setBurnIn(s.burn_in);
    OT::RandomGenerator::SetSeed(static_cast<OT::UnsignedInteger>(s.seed));
    const OT::Sample chain = sampler.getSample(s.samples);
    out.acceptance = sampler.getAcceptanceRate();
    const std::size_t kept = std::min<std::size_t>(s.draws, chain.getSize());
    for (std::size_t i = 0; i < kept; ++i) {
      // The middle of each of `kept` equal stretches of the chain: far apart, so nearly independent.
      const OT::Point u_i = chain[(2 * i + 1) * chain.getSize() / (2 * kept)];
      std::vector<double> x;
      for (std::size_t j = 0; j < p; ++j) x.push_back(d.lower[j] + u_i[j] * (d.upper[j] - d.lower[j]));
      out.draws.push_back(std::move(x));
    }
    const double a = (1 - s.confidence) / 2;
    for (std::size_t j = 0; j < p; ++j) {
      const OT::Sample m = chain.getMarginal(j);
      auto phys = [&](double v) { return d.lower[j] + v * (d.upper[j] - d.lower[j]); };
      out.parameters.push_back({d.names[j], d.points[best][j], phys(m.computeMean()[0]), phys(m.computeMedian()[0]),
                                phys(m.computeQuantile(a)[0]), phys(m.computeQuantile(1 - a)[0])});
    }
  } catch (const OT::Exception& e) {
    detail::rethrow(e);
  }
  return out;
}

MisfitData load_calibration_misfit(const std::string& db_file, const std::string& name) {
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
  if (d.points.size() < 2 * d.names.size() + 2)
    throw InputError(db_file, "--calibration",
                     "'" + name + "' has " + std::to_string(d.points.size()) +
                         " distinct evaluations; the misfit surrogate needs at least " +
                         std::to_string(2 * d.names.size() + 2) + " (run the calibration with its profile)");
  return d;
}

std::string predictive_spec(const MisfitData& d, const Posterior& post, const std::string& calibration,
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
