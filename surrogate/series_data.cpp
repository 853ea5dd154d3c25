#include "surrogate/series_data.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "calibration/evaluator.h"
#include "calibration/objective.h"
#include "calibration/stored_spec.h"
#include "campaigns/spec.h"
#include "common/errors.h"
#include "store/db/campaign_store.h"

namespace flume::surrogate {

SeriesData load_calibration_series(const std::string& db_file, const std::string& name, int rounds_before) {
  using json = nlohmann::json;
  namespace fs = std::filesystem;
  store::CampaignStore db(db_file, /*read_only=*/true);
  const auto c = db.find_campaign(name);
  if (!c) throw InputError(db_file, "--calibration", "no calibration named '" + name + "'");
  {
    const json stored = json::parse(c->spec);
    if (!stored.contains("parameters") || !stored.contains("objective"))
      throw InputError(db_file, "--calibration", "'" + name + "' is a campaign, not a calibration");
  }
  const calibration::CalibrationSpec spec =
      calibration::parse_stored_calibration_spec(c->spec, db_file + " (calibration '" + name + "')");
  const calibration::Objective objective(spec.objective, spec.targets, spec.file);
  double weighted_samples = 0;  // sum_g w_g n_g, the RMS's denominator
  for (const auto& w : objective.windows()) weighted_samples += w.weight * static_cast<double>(w.time.size());

  SeriesData d;
  d.spec_json = c->spec;
  d.n_residuals = weighted_samples;
  for (const auto& p : spec.parameters) {
    d.names.push_back(p.path);
    d.lower.push_back(p.lower);
    d.upper.push_back(p.upper);
  }
  // A point evaluated twice (replayed) counts once.
  std::map<std::vector<double>, std::vector<double>> unique;
  for (const auto& e : db.evaluations(c->id)) {
    if (e.phase == kRefinePhase && e.start >= rounds_before) continue;
    const json params = json::parse(e.params_json), terms = json::parse(e.terms_json);
    if (terms.contains("failed") || !terms.contains("rms_m") || !terms["rms_m"].is_number()) continue;
    std::vector<double> x, run_values;
    double shift = 0;
    for (const auto& p : spec.parameters) {
      x.push_back(params.at(p.path).get<double>());
      if (p.needs_run)
        run_values.push_back(x.back());
      else
        shift = x.back();
    }
    if (unique.count(x)) continue;
    const auto run = db.find_run(c->id, campaigns::text_hash(calibration::run_params_json(spec, run_values)));
    if (!run)
      throw InputError(db_file, "--calibration", "evaluation " + e.params_json + " has no run in the store");
    // The store keeps absolute paths; a store moved with its runs folder is read beside its new place.
    std::string h5 = run->h5_path;
    if (!fs::exists(h5))
      h5 = (fs::path(db_file + ".runs") / name / fs::path(run->run_dir).filename() / "result.h5").string();
    std::map<std::string, calibration::SimRecord> sim;
    try {
      for (const auto& t : spec.targets) sim[t.gauge] = calibration::read_sim_gauge(h5, t.gauge);
    } catch (const std::exception& ex) {
      throw InputError(h5, "--calibration",
                       std::string("the run's gauge record cannot be read: ") + ex.what());
    }
    std::vector<double> r = objective.residuals(sim, shift);
    // The same residuals as the calibration's, or the run is not the one evaluated: its RMS must come back.
    double ssr = 0;
    for (double v : r) ssr += v * v;
    const double rms = terms["rms_m"].get<double>(), again = std::sqrt(ssr / weighted_samples);
    if (std::fabs(again - rms) > 1e-9 * rms + 1e-15)
      throw InputError(h5, "--calibration",
                       "gives an RMS of " + std::to_string(again) + " m where the calibration stored " +
                           std::to_string(rms) + " m: the run is not the one evaluated");
    unique[x] = std::move(r);
  }
  for (auto& [x, r] : unique) {
    d.points.push_back(x);
    d.residuals.push_back(std::move(r));
  }
  if (d.points.size() < posterior_min_evaluations(d.names.size()))
    throw InputError(db_file, "--calibration",
                     "'" + name + "' has " + std::to_string(d.points.size()) +
                         " distinct evaluations; the series emulator needs at least " +
                         std::to_string(posterior_min_evaluations(d.names.size())) +
                         " (run the calibration with its profile)");
  return d;
}

}  // namespace flume::surrogate
