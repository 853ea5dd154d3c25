#include "surrogate/stored.h"

#include "common/errors.h"
#include "report/campaign_data.h"

namespace flume::surrogate {

StoredFit fit_and_store(const std::string& db_file, const std::string& campaign, const std::string& metric,
                        const FitSettings& requested, bool force) {
  TrainingData data = load_training_data(db_file, campaign, metric, 4, requested.given);
  FitSettings settings = requested;
  if (!settings.validation.empty()) {
    // The validation campaign's runs go last: they are the held-back ones.
    if (settings.holdout > 0) throw InputError("command line", "--validation", "and --holdout exclude each other");
    const TrainingData v = load_training_data(db_file, settings.validation, metric, 1, settings.given);
    if (v.inputs != data.inputs)
      throw InputError(db_file, "--validation",
                       "campaign '" + v.campaign + "' has other parameters than '" + data.campaign + "'");
    data.x.insert(data.x.end(), v.x.begin(), v.x.end());
    data.y.insert(data.y.end(), v.y.begin(), v.y.end());
    data.run_ids.insert(data.run_ids.end(), v.run_ids.begin(), v.run_ids.end());
    settings.holdout = v.y.size();
    data.x_outside.insert(data.x_outside.end(), v.x_outside.begin(), v.x_outside.end());
    data.outside_held_back = v.x_outside.size();
  }
  const std::string hash = fit_hash(data, settings);
  store::CampaignStore db(db_file);
  StoredFit out;
  if (auto existing = db.find_surrogate(data.campaign_id, metric, to_string(settings.kind));
      existing && existing->runs_hash == hash && !force) {
    out.record = *existing;
    return out;
  }
  const FitResult r = fit_surrogate(data, settings);
  store::SurrogateRecord rec;
  rec.campaign = data.campaign_id;
  rec.metric = metric;
  rec.kind = to_string(settings.kind);
  rec.settings_json = settings_json(settings);
  rec.runs_json = runs_json(r);
  rec.runs_hash = hash;
  rec.quality_json = quality_json(r, data, settings);
  rec.model = r.model;
  db.save_surrogate(rec);
  out.record = *db.find_surrogate(data.campaign_id, metric, rec.kind);
  out.refitted = true;
  return out;
}

store::SurrogateRecord stored_surrogate(const std::string& db_file, const std::string& campaign,
                                        const std::string& metric, Kind kind) {
  const report::CampaignData c = report::load_campaign(db_file, campaign);
  store::CampaignStore db(db_file, /*read_only=*/true);
  auto r = db.find_surrogate(c.record.id, metric, to_string(kind));
  if (!r)
    throw InputError(db_file, "--metric",
                     std::string("no ") + to_string(kind) + " surrogate of '" + metric + "' in campaign '" +
                         c.record.name + "': run `flume surrogate fit` first");
  return *r;
}

std::vector<store::SurrogateRecord> stored_surrogate_list(const std::string& db_file, const std::string& campaign) {
  const report::CampaignData c = report::load_campaign(db_file, campaign);
  store::CampaignStore db(db_file, /*read_only=*/true);
  return db.surrogates(c.record.id, /*with_model=*/false);
}

}  // namespace flume::surrogate
