#include "surrogate/adaptive_campaign.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "campaigns/engine.h"
#include "campaigns/spec.h"
#include "common/errors.h"
#include "report/campaign_data.h"
#include "surrogate/stored.h"

namespace flume::surrogate {
namespace {

using json = nlohmann::json;

// The points earlier batches added: the store's design points beyond the spec's own design.
void append_stored_points(campaigns::CampaignSpec& spec, const std::string& db_file, std::size_t base) {
  spec.points.values.resize(base);
  {
    store::CampaignStore probe(db_file);
    if (!probe.find_campaign(spec.name)) return;
  }
  const report::CampaignData c = report::load_campaign(db_file, spec.name);
  for (const auto& row : c.rows) {
    if (row.design_index < static_cast<std::int64_t>(base)) continue;
    std::vector<double> x;
    for (std::size_t j = 0; j < spec.parameters.size(); ++j) {
      const auto& v = row.params.at(static_cast<std::size_t>(c.parameter_index(spec.parameters[j].path)));
      x.push_back(design_value(spec.parameters[j].distribution, v.is_text, v.number, v.text));
    }
    spec.points.values.push_back(std::move(x));
  }
}

// The kriging just stored (fitted to the same runs the proposal starts from).
std::string db_model(const std::string& db_file, const std::string& campaign, const std::string& metric) {
  return stored_surrogate(db_file, campaign, metric, Kind::kKriging).model;
}

}  // namespace

AdaptiveCampaignOutcome run_adaptive_campaign(const AdaptiveCampaignOptions& o) {
  campaigns::CampaignSpec spec = campaigns::load_campaign_spec(o.spec_file);
  if (spec.listed) throw InputError(o.spec_file, "design", "an adaptive campaign needs a sampled design, not a list");
  if (o.target_width > 0 && o.adapt.criterion != Criterion::kExceedance)
    throw InputError("command line", "--target-width", "needs --threshold (the exceedance criterion)");
  const std::size_t base = spec.points.values.size();
  if (base > o.max_runs)
    throw InputError("command line", "--max-runs",
                     "is below the spec's first design (" + std::to_string(base) + " runs)");
  campaigns::EngineOptions eopt;
  eopt.db_file = o.db_file;
  eopt.local_workers = o.workers;
  AdaptiveCampaignOutcome out;
  append_stored_points(spec, o.db_file, base);
  for (;;) {
    out.exit_code = campaigns::run_campaign(spec, eopt, 1);
    if (out.exit_code > 128) return out;  // stopped by a signal: run again to continue
    FitSettings fs;
    fs.kind = Kind::kKriging;
    fs.folds = o.folds;
    fs.seed = o.adapt.seed;
    // The exceedance interval needs the conditional realisations; the variance criterion only Q2.
    fs.bootstrap = o.adapt.criterion == Criterion::kExceedance ? 200 : 0;
    fs.mc_size = 4000;
    if (o.adapt.criterion == Criterion::kExceedance) fs.thresholds = {o.adapt.threshold};
    const StoredFit fit = fit_and_store(o.db_file, spec.name, o.metric, fs);
    const TrainingData data = load_training_data(o.db_file, spec.name, o.metric);
    const json q = json::parse(fit.record.quality_json);
    out.runs = spec.points.values.size();
    out.q2 = q["q2_cv"].is_number() ? q["q2_cv"].get<double>() : 0.0;
    if (o.adapt.criterion == Criterion::kExceedance) {
      const json& c = q["exceedance"];
      out.p = c["p"][0].get<double>();
      out.width = c["hi"][0].is_number() ? c["hi"][0].get<double>() - c["lo"][0].get<double>() : 1.0;
    }
    std::printf("adapt: %zu design points, %zu runs fitted, kriging Q2 %zu-fold %.4f", out.runs, data.y.size(),
                q["folds"].get<std::size_t>(), out.q2);
    if (o.adapt.criterion == Criterion::kExceedance)
      std::printf(", P(%s > %g) = %.4f, interval width %.4f", o.metric.c_str(), o.adapt.threshold, out.p, out.width);
    std::printf("\n");
    std::fflush(stdout);
    // A width is evidence only once runs lie on both sides of the threshold: with every run on one side the
    // kriging's realisations can all stay there, and the interval reads zero wide however little is known.
    bool above = false, below = false;
    for (const double y : data.y) (y > o.adapt.threshold ? above : below) = true;
    const bool width_counts = o.target_width > 0 && above && below;
    if (o.target_width > 0 && !width_counts)
      std::printf("adapt: every run so far is %s %g: the interval's width is not yet evidence, going on\n",
                  above ? "above" : "at or below", o.adapt.threshold);
    out.reached = (o.target_q2 > 0 && out.q2 >= o.target_q2) || (width_counts && out.width <= o.target_width);
    if (out.reached || out.runs >= o.max_runs) return out;
    AdaptiveSettings a = o.adapt;
    a.batch = std::min(a.batch, o.max_runs - out.runs);
    const Proposal p = propose_batch(data, a, db_model(o.db_file, spec.name, o.metric));
    for (const auto& x : p.points) spec.points.values.push_back(x);
    ++out.batches;
  }
}

}  // namespace flume::surrogate
