// A campaign spec: JSON parsed and validated once (spec.cpp) into these plain structs. Nothing here touches
// the database: a spec that fails validation leaves the store as it was.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "sampling/design.h"
#include "sampling/distribution.h"

namespace flume::campaigns {

struct ParameterSpec {
  std::string path;  // a scene path ("debris.friction.flume") or a model input ("x1")
  sampling::Distribution distribution;
};

// How each run is executed; not part of the campaign's identity (changing it does not change the results).
struct RunSettings {
  double time_limit_s = 3600.0;
  int threads = 1;
  double memory_limit_mb = 0.0;  // address-space limit per run; 0: none
  double checkpoint_every_s = 0; // > 0: each run checkpoints this often (wall s) and a redone run resumes
  std::string output_dir;        // empty: "<db>.runs/<campaign>" next to the database
};

struct CampaignSpec {
  std::string file;  // where it was read from, for messages
  std::string name;
  std::string description;
  std::string scene;        // absolute path of the scene file; empty for a model
  std::string model;        // analytic model name ("ishigami", "test"); empty for a scene
  std::vector<std::pair<std::string, std::string>> overrides;  // fixed: path -> JSON text of the value
  std::vector<ParameterSpec> parameters;
  std::vector<sampling::RankCorrelation> correlations;
  sampling::DesignSpec design;
  // A `list` design (`"design": {"type": "list", "points": [{path: value, ...}, ...]}`): the points are given
  // one by one, as a study of chosen settings needs (a fidelity ladder, a set of variants). Each path met in
  // any point becomes a `choice` parameter over the values given for it; a point that does not name a path
  // leaves the scene's value (its design value is NaN: no `--set`, NULL in the store). Two keys are not scene
  // paths: `scene` (another scene file for that point: a variant; it is a parameter, so the store shows it)
  // and `label` (a name for tables, not a parameter).
  bool listed = false;
  std::vector<std::string> point_labels;  // listed: one per point ("" when none given)
  std::vector<std::string> point_scenes;  // listed: absolute scene file of each point (spec.scene when not set)
  std::uint64_t seed = 0;
  RunSettings run;
  std::string canonical;  // the spec's identity as canonical JSON (sorted keys, without `run`/`description`)
  std::string hash;       // of `canonical`: a changed spec under the same name is refused
  sampling::Design points;  // the design generated from the above (deterministic in the seed)
};

// Reads and validates a spec; throws flume::InputError naming the file and the field path. Parameter paths
// are checked against the scene (flume::load_scene with the overrides and each parameter set) or the model's
// inputs, and every point of the design is checked against the scene's allowed ranges.
CampaignSpec load_campaign_spec(const std::string& file);
CampaignSpec parse_campaign_spec(const std::string& json_text, const std::string& file_label,
                                 const std::string& base_dir);

// Only the model name, the parameters and their correlations of a spec (a stored campaign's, read back to
// know its input distributions): no scene or design checks, no design generated.
CampaignSpec parse_spec_parameters(const std::string& json_text, const std::string& file_label);

// The parameter path of a list design that selects the scene file rather than setting a scene value.
inline constexpr const char* kScenePath = "scene";

// True when design point `index` gives parameter `j` a value (always, except in list designs).
bool has_value(const CampaignSpec& spec, size_t index, size_t j);

// JSON text of a parameter value for `--set path=value` and for the store's JSON column.
std::string value_json(const ParameterSpec& p, double value);

// 64-bit FNV-1a of a text, as 16 hex digits: stable across builds and machines.
std::string text_hash(const std::string& text);

}  // namespace flume::campaigns
