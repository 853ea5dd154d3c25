#include "surrogate/stored.h"

#include "common/errors.h"
#include "report/campaign_data.h"

namespace flume::surrogate {

StoredFit fit_and_store(const std::string& db_file, const std::string& campaign, const std::string& metric,
                        const FitSettings& settings, bool force) {
  const TrainingData data = load_training_data(db_file, campaign, metric);
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
