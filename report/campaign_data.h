// A campaign as the report reads it: one read-only pass over the store, into plain structs. Nothing in the
// report touches SQLite or JSON past this layer.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "store/db/campaign_store.h"

namespace flume::report {

struct ParameterInfo {
  std::string path;
  bool is_text = false;
};

// One design point (design order). A repeated point shares its run with the first one.
struct RunRow {
  std::int64_t design_index = 0;
  std::int64_t run_id = 0;
  store::RunStatus status = store::RunStatus::kPending;
  std::string message;
  std::vector<store::ParamValue> params;  // in parameter order
  std::map<std::string, double> metrics;  // finite values only (the store keeps NaN/Inf as NULL)
  bool ok() const { return status == store::RunStatus::kOk; }
};

struct CampaignData {
  std::string db_file;
  store::CampaignRecord record;
  std::string model;        // analytic model name, empty for a scene campaign
  std::string scene;        // scene file of a scene campaign
  std::string design_type;  // "monte_carlo", "lhs", "sobol", "grid", "one_at_a_time", "saltelli"
  std::size_t saltelli_base_size = 0;
  // Monte Carlo, LHS and Sobol' designs: the spec's sample count. Design points beyond it were added by
  // `flume surrogate adapt` where its surrogate was least sure: not draws of the input law. 0: unknown.
  std::size_t design_samples = 0;
  // Fixed values: the spec's overrides, then (where the scene file is readable) the few scene values the
  // report asks for (obstacles.layout); key -> value.
  std::map<std::string, store::ParamValue> fixed;
  std::map<std::string, std::string> fixed_source;  // key -> "overrides" | "scene"
  std::vector<ParameterInfo> parameters;
  std::vector<RunRow> rows;
  std::vector<std::string> metric_names;  // every metric name any run reported, sorted

  bool is_saltelli() const { return design_type == "saltelli" && saltelli_base_size > 0; }
  // Index of a parameter path, or -1.
  int parameter_index(const std::string& path) const;
};

// Reads a campaign. Throws flume::InputError naming the file (not a flume store) or the campaign (unknown,
// with the names the store has); an empty name picks the store's only campaign.
CampaignData load_campaign(const std::string& db_file, const std::string& campaign_name);

}  // namespace flume::report
