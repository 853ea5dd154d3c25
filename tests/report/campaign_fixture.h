// Builds a campaign in a store without the process engine: the spec is parsed and planned by the campaign
// code itself, then every run is claimed and recorded through the store API with outcomes computed here.
// Thousands of runs take seconds this way (the engine spends ~0.3 s per run on process start-up).
#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "campaigns/engine.h"
#include "campaigns/spec.h"
#include "common/version.h"
#include "store/db/campaign_store.h"

namespace flume::test {

// `evaluate(values, design_index)` gives each run's outcome (values in parameter order; a choice holds the
// index of its value).
using Evaluate = std::function<store::RunOutcome(const std::vector<double>&, std::int64_t)>;

// A spec already parsed (a study's campaign, say); returns the campaign's id.
inline std::int64_t make_campaign(const std::string& db_file, const campaigns::CampaignSpec& spec,
                                  const Evaluate& evaluate) {
  store::CampaignStore db(db_file);
  store::CampaignRecord rec;
  rec.name = spec.name;
  rec.spec = spec.canonical;
  rec.spec_hash = spec.hash;
  rec.code_version = build_info::version();
  const auto planned = campaigns::plan_runs(spec);
  rec.design_size = static_cast<std::int64_t>(planned.size());
  rec.saltelli_base_size = static_cast<std::int64_t>(spec.points.saltelli_base_size);
  std::vector<store::ParameterColumn> cols;
  for (const auto& p : spec.parameters) cols.push_back({p.path, p.distribution.is_text_choice()});
  const std::int64_t id = db.create_campaign(rec, cols, planned);
  while (auto t = db.claim_next(id, "test", "fixture")) {
    store::RunOutcome out = evaluate(spec.points.values[t->design_index], t->design_index);
    db.record_outcome(t->run_id, out);
  }
  return id;
}

inline campaigns::CampaignSpec make_campaign(const std::string& db_file, const std::string& spec_json,
                                             const Evaluate& evaluate) {
  const campaigns::CampaignSpec spec = campaigns::parse_campaign_spec(spec_json, "spec.json", "");
  make_campaign(db_file, spec, evaluate);
  return spec;
}

inline store::RunOutcome ok_outcome(std::vector<std::pair<std::string, double>> metrics) {
  store::RunOutcome o;
  o.status = store::RunStatus::kOk;
  o.metrics = std::move(metrics);
  return o;
}

}  // namespace flume::test
