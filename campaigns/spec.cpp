// Campaign spec JSON -> CampaignSpec, checked once here: every error names the file, the field path and
// what is allowed, and is raised before anything touches the database.
#include "campaigns/spec.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "campaigns/models.h"
#include "campaigns/run_folders.h"
#include "common/errors.h"
#include "campaigns/spec_fields.h"
#include "common/input/field_reader.h"
#include "common/input/json_input.h"
#include "solver/scene.h"

namespace flume::campaigns {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

using input::type_name;

using Reader = input::FieldReader;
using input::Bounds;
constexpr double kInf = std::numeric_limits<double>::infinity();

using sampling::DesignType;
using sampling::Distribution;
using sampling::DistributionType;

Distribution read_distribution(Reader& r) {
  Distribution d;
  d.type = r.choice<DistributionType>("type",
                                      {{"uniform", DistributionType::kUniform},
                                       {"normal", DistributionType::kNormal},
                                       {"lognormal", DistributionType::kLogNormal},
                                       {"truncated_normal", DistributionType::kTruncatedNormal},
                                       {"beta", DistributionType::kBeta},
                                       {"choice", DistributionType::kChoice}});
  switch (d.type) {
    case DistributionType::kUniform:
      d.lower = r.number("lower");
      d.upper = r.number("upper");
      break;
    case DistributionType::kNormal:
      d.mean = r.number("mean");
      d.std = r.number("std");
      break;
    case DistributionType::kLogNormal:
      if (r.has("mu_log") || r.has("sigma_log")) {
        d.mu_log = r.number("mu_log");
        d.sigma_log = r.number("sigma_log");
      } else {
        if (!r.has("mean")) r.fail("mean", "is required (a lognormal takes mean and std of the variable, or mu_log and sigma_log)");
        const double mean = r.number("mean", Bounds{0.0, kInf, true, true});
        const double std = r.number("std");
        d = sampling::lognormal_from_mean_std(mean, std);
      }
      break;
    case DistributionType::kTruncatedNormal:
      d.mean = r.number("mean");
      d.std = r.number("std");
      d.lower = r.number("lower");
      d.upper = r.number("upper");
      break;
    case DistributionType::kBeta:
      d.alpha = r.number("alpha");
      d.beta = r.number("beta");
      d.lower = r.number_or("lower", 0.0);
      d.upper = r.number_or("upper", 1.0);
      break;
    case DistributionType::kChoice: {
      const json& values = r.array("values");
      if (!r.has("values")) r.fail("values", "is required (an array of numbers or of strings)");
      for (size_t i = 0; i < values.size(); ++i) {
        if (values[i].is_number()) {
          d.numeric_choices.push_back(values[i].get<double>());
        } else if (values[i].is_string()) {
          d.text_choices.push_back(values[i].get<std::string>());
        } else {
          r.fail("values." + std::to_string(i), std::string("must be a number or a string, got ") + type_name(values[i]));
        }
      }
      const json& weights = r.array("weights");
      for (size_t i = 0; i < weights.size(); ++i) {
        if (!weights[i].is_number()) r.fail("weights." + std::to_string(i), "must be a number");
        d.weights.push_back(weights[i].get<double>());
      }
      std::set<std::string> seen;
      for (size_t i = 0; i < values.size(); ++i)
        if (!seen.insert(values[i].dump()).second)
          r.fail("values." + std::to_string(i), "repeats the value " + values[i].dump() + " (use weights instead)");
      break;
    }
  }
  const std::string problem = sampling::check_distribution(d);
  if (!problem.empty()) {
    const auto colon = problem.find(": ");
    r.fail(problem.substr(0, colon), problem.substr(colon + 2));
  }
  r.finish();
  return d;
}

// Where a relative scene path points: the current directory first (as a user typing the command expects),
// then the spec's folder (a spec kept next to its scene).
std::string resolve_scene(const std::string& path, const std::string& base_dir) {
  fs::path p(path);
  if (p.is_absolute()) return p.lexically_normal().string();
  std::error_code ec;
  if (fs::exists(p, ec)) return fs::absolute(p, ec).lexically_normal().string();
  if (!base_dir.empty() && fs::exists(fs::path(base_dir) / p, ec))
    return fs::absolute(fs::path(base_dir) / p, ec).lexically_normal().string();
  return "";
}


// The overrides and the values design point k of a list design sets, as `--set` pairs (not its scene).
std::vector<std::pair<std::string, std::string>> list_point_sets(const CampaignSpec& spec, size_t k) {
  std::vector<std::pair<std::string, std::string>> sets = spec.overrides;
  for (size_t j = 0; j < spec.parameters.size(); ++j)
    if (has_value(spec, k, j) && spec.parameters[j].path != kScenePath)
      sets.emplace_back(spec.parameters[j].path, value_json(spec.parameters[j], spec.points.values[k][j]));
  return sets;
}

// Each point of a list design against its own scene (or the model): an error names the point and, where the
// scene says which, the path of that point it rejects.
void validate_list_points(const CampaignSpec& spec) {
  std::map<std::string, std::string> texts;  // scene file -> its text
  for (size_t k = 0; k < spec.points.values.size(); ++k) {
    const std::string at = "design.points." + std::to_string(k);
    const auto sets = list_point_sets(spec, k);
    auto field_of = [&](const std::string& field) {
      for (size_t j = 0; j < spec.parameters.size(); ++j) {
        const std::string& path = spec.parameters[j].path;
        if (has_value(spec, k, j) && (field == path || field.rfind(path + ".", 0) == 0 || path.rfind(field + ".", 0) == 0))
          return at + "." + path;
      }
      for (const auto& [path, value] : spec.overrides)
        if (field == path || field.rfind(path + ".", 0) == 0 || path.rfind(field + ".", 0) == 0) return "overrides." + path;
      return at;
    };
    if (!spec.model.empty()) {
      const std::string p = check_model_inputs(spec.model, sets);
      if (!p.empty()) throw InputError(spec.file, field_of(p.substr(0, p.find(':'))), "rejected by model " + spec.model + ": " + p);
      continue;
    }
    const std::string& scene = spec.point_scenes.at(k);
    if (!texts.count(scene)) texts[scene] = read_scene_file(scene);
    std::vector<Override> all;
    for (const auto& [path, value] : sets) all.push_back({path, value});
    try {
      parse_scene_text(texts[scene], scene, all);
    } catch (const InputError& e) {
      throw InputError(spec.file, field_of(e.field()), "rejected by the scene: " + std::string(e.what()));
    }
  }
}

// Reads `design.points` of a list design into choice parameters and their value indices (see spec.h).
void read_list_design(Reader& d, const json& design_json, CampaignSpec& spec, const std::string& base_dir) {
  const json& points = d.array("points");
  if (points.empty()) d.fail("points", "is required: a non-empty array of objects {\"label\": ..., path: value, ...}");
  std::vector<std::string> paths;
  std::map<std::string, std::vector<json>> values;  // path -> its distinct values, in order of appearance
  std::vector<std::map<std::string, json>> given(points.size());
  std::set<std::string> labels;
  for (size_t i = 0; i < points.size(); ++i) {
    // A point: a label and scene paths (free keys); the reference describes it in design.points.
    static const input::ObjectDoc point_doc{
        "design.points[]", "", {input::string("label", "the point's name in tables and plots")}, true};
    Reader p(points[i], point_doc, "design.points." + std::to_string(i), spec.file);
    std::string label, scene;
    for (auto it = design_json["points"][i].begin(); it != design_json["points"][i].end(); ++it) {
      const std::string& key = it.key();
      if (key == "label") {
        label = p.string_or("label", "");
        if (!labels.insert(label).second) p.fail("label", "'" + label + "' is already the label of another point");
        continue;
      }
      p.accept(key);
      const json& v = it.value();
      if (key == kScenePath) {
        if (!v.is_string()) p.fail(key, std::string("must be a scene file (a string), got ") + type_name(v));
        if (resolve_scene(v.get<std::string>(), base_dir).empty())
          p.fail(key, "cannot open '" + v.get<std::string>() + "' (looked in the current directory and next to the spec)");
      } else if (!v.is_number() && !v.is_string()) {
        p.fail(key, std::string("must be a number or a string, got ") + type_name(v));
      }
      for (const auto& [path, fixed] : spec.overrides)
        if (path == key) p.fail(key, "'" + key + "' is also a fixed override");
      if (!values.count(key)) paths.push_back(key);
      auto& seen = values[key];
      if (!seen.empty() && seen.front().is_string() != v.is_string())
        p.fail(key, std::string("is ") + type_name(v) + " here but " + type_name(seen.front()) + " in an earlier point");
      if (std::find(seen.begin(), seen.end(), v) == seen.end()) seen.push_back(v);
      given[i][key] = v;
    }
    p.finish();
    spec.point_labels.push_back(label);
    spec.point_scenes.push_back(given[i].count(kScenePath)
                                    ? resolve_scene(given[i][kScenePath].get<std::string>(), base_dir)
                                    : spec.scene);
    if (!spec.model.empty() && given[i].count(kScenePath))
      p.fail(kScenePath, "a model campaign has no scene to replace");
  }
  for (const auto& path : paths) {
    ParameterSpec ps;
    ps.path = path;
    ps.distribution.type = DistributionType::kChoice;
    for (const auto& v : values[path]) {
      if (v.is_string())
        ps.distribution.text_choices.push_back(v.get<std::string>());
      else
        ps.distribution.numeric_choices.push_back(v.get<double>());
    }
    spec.parameters.push_back(ps);
  }
  spec.points.values.assign(points.size(), std::vector<double>(paths.size(), std::nan("")));
  for (size_t i = 0; i < points.size(); ++i)
    for (size_t j = 0; j < paths.size(); ++j) {
      auto it = given[i].find(paths[j]);
      if (it == given[i].end()) continue;
      const auto& seen = values[paths[j]];
      spec.points.values[i][j] = static_cast<double>(std::find(seen.begin(), seen.end(), it->second) - seen.begin());
    }
}

// Checks that the scene (or model) accepts the overrides, each parameter path, and every design point.
// The design points checked up front, in order: every point of a design of up to kCheckedPoints, and beyond
// that the first kCheckedPoints plus, for each parameter, the points where it is smallest and largest. Each
// check parses the scene, so checking all of a 10^7-point design would take hours before anything runs (a
// fuzzer found a 200,200-point design taking over 10 s); a point past the bound that the scene still rejects
// fails as that run's input error, recorded with its message, and the others run.
constexpr size_t kCheckedPoints = 1000;

std::vector<size_t> points_to_check(const sampling::Design& design, size_t np) {
  const size_t n = design.values.size();
  std::vector<size_t> ks;
  for (size_t k = 0; k < std::min(n, kCheckedPoints); ++k) ks.push_back(k);
  if (n <= kCheckedPoints) return ks;
  for (size_t j = 0; j < np; ++j) {
    size_t lo = 0, hi = 0;
    for (size_t k = 1; k < n; ++k) {
      if (design.values[k][j] < design.values[lo][j]) lo = k;
      if (design.values[k][j] > design.values[hi][j]) hi = k;
    }
    ks.push_back(lo);
    ks.push_back(hi);
  }
  return ks;
}

void validate_against_target(const CampaignSpec& spec, const sampling::Design& design) {
  const size_t np = spec.parameters.size();
  auto point_sets = [&](size_t k) {
    std::vector<std::pair<std::string, std::string>> sets = spec.overrides;
    for (size_t j = 0; j < np; ++j)
      sets.emplace_back(spec.parameters[j].path, value_json(spec.parameters[j], design.values[k][j]));
    return sets;
  };
  // Which parameter a failure belongs to: the one whose path the target named, else the last one tried.
  auto owner = [&](const std::string& field) -> std::string {
    for (size_t j = 0; j < np; ++j)
      if (field == spec.parameters[j].path || field.rfind(spec.parameters[j].path + ".", 0) == 0 ||
          spec.parameters[j].path.rfind(field + ".", 0) == 0)
        return "parameters." + std::to_string(j) + ".distribution";
    return "parameters";
  };

  if (spec.listed) {
    validate_list_points(spec);
    return;
  }
  if (!spec.model.empty()) {
    std::string p = check_model_inputs(spec.model, spec.overrides);
    if (!p.empty()) throw InputError(spec.file, "overrides." + p.substr(0, p.find(':')), p.substr(p.find(": ") + 2));
    for (size_t j = 0; j < np; ++j) {
      p = check_model_inputs(spec.model, {{spec.parameters[j].path, value_json(spec.parameters[j], design.values[0][j])}});
      if (!p.empty() && p.find("not an input") != std::string::npos)
        throw InputError(spec.file, "parameters." + std::to_string(j) + ".path", p);
    }
    for (const size_t k : points_to_check(design, np)) {
      p = check_model_inputs(spec.model, point_sets(k));
      if (!p.empty())
        throw InputError(spec.file, owner(p.substr(0, p.find(':'))),
                         "design point " + std::to_string(k) + " is rejected by model " + spec.model + ": " + p);
    }
    return;
  }

  const std::string text = read_scene_file(spec.scene);
  std::vector<Override> fixed;
  for (const auto& [path, value] : spec.overrides) fixed.push_back({path, value});
  try {
    parse_scene_text(text, spec.scene, fixed);
  } catch (const InputError& e) {
    throw InputError(spec.file, "overrides", "the scene rejects the overrides: " + std::string(e.what()));
  }
  // Each path alone, at its first design value: an unknown path is reported against that parameter.
  for (size_t j = 0; j < np; ++j) {
    std::vector<Override> one = fixed;
    one.push_back({spec.parameters[j].path, value_json(spec.parameters[j], design.values[0][j])});
    try {
      parse_scene_text(text, spec.scene, one);
    } catch (const InputError& e) {
      if (e.field() == spec.parameters[j].path || spec.parameters[j].path.rfind(e.field() + ".", 0) == 0 ||
          e.problem().find("unknown field") != std::string::npos || e.problem().find("no such") != std::string::npos ||
          e.problem().find("cannot set") != std::string::npos || e.problem().find("empty segment") != std::string::npos)
        throw InputError(spec.file, "parameters." + std::to_string(j) + ".path",
                         "'" + spec.parameters[j].path + "' is not a field of the scene: " + e.what());
      throw InputError(spec.file, "parameters." + std::to_string(j) + ".distribution",
                       "design point 0 is rejected by the scene: " + std::string(e.what()));
    }
  }
  for (const size_t k : points_to_check(design, np)) {
    std::vector<Override> all;
    for (const auto& [path, value] : point_sets(k)) all.push_back({path, value});
    try {
      parse_scene_text(text, spec.scene, all);
    } catch (const InputError& e) {
      throw InputError(spec.file, owner(e.field()),
                       "design point " + std::to_string(k) + " is rejected by the scene: " + e.what());
    }
  }
}

}  // namespace

std::string text_hash(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

bool has_value(const CampaignSpec& spec, size_t index, size_t j) {
  return !spec.listed || std::isfinite(spec.points.values.at(index).at(j));
}

std::string value_json(const ParameterSpec& p, double value) {
  if (!std::isfinite(value)) return "null";  // a list design's point that leaves the path alone
  const auto& d = p.distribution;
  if (d.type == DistributionType::kChoice) {
    const auto i = static_cast<size_t>(std::llround(value));
    if (d.is_text_choice()) return json(d.text_choices.at(i)).dump();
    return json(d.numeric_choices.at(i)).dump();
  }
  return json(value).dump();  // shortest text that reads back to the same double
}

// The `parameters` and `correlation` sections (shared by the full parse and parse_spec_parameters).
static void read_parameters(Reader& root, const json& root_json, CampaignSpec& spec) {
  const json& params = root.array("parameters");
  if (spec.listed && !params.empty())
    root.fail("parameters", "must be absent with a list design (its points name the paths they set)");
  if (params.empty() && !spec.listed)
    root.fail("parameters", "is required: a non-empty array of {path, distribution}");
  (void)root_json;
  std::set<std::string> paths;
  for (size_t i = 0; i < params.size(); ++i) {
    Reader p(params[i], *campaign_doc().find("parameters")->object, "parameters." + std::to_string(i), spec.file);
    ParameterSpec ps;
    ps.path = p.string("path");
    if (ps.path.empty()) p.fail("path", "must not be empty");
    if (!paths.insert(ps.path).second) p.fail("path", "'" + ps.path + "' is already a parameter");
    for (const auto& [path, value] : spec.overrides)
      if (path == ps.path) p.fail("path", "'" + ps.path + "' is also a fixed override");
    if (!p.has("distribution")) p.fail("distribution", "is required (an object with a type)");
    Reader d = p.object("distribution");
    ps.distribution = read_distribution(d);
    p.finish();
    spec.parameters.push_back(ps);
  }

  const json& corr = root.array("correlation");
  if (spec.listed && !corr.empty()) root.fail("correlation", "must be absent with a list design");
  for (size_t i = 0; i < corr.size(); ++i) {
    Reader c(corr[i], *campaign_doc().find("correlation")->object, "correlation." + std::to_string(i), spec.file);
    const json& pair = c.array("parameters");
    if (pair.size() != 2 || !pair[0].is_string() || !pair[1].is_string())
      c.fail("parameters", "must be an array of two parameter paths");
    sampling::RankCorrelation rc;
    auto index_of = [&](const std::string& path, int k) {
      for (size_t j = 0; j < spec.parameters.size(); ++j)
        if (spec.parameters[j].path == path) return j;
      c.fail("parameters." + std::to_string(k), "'" + path + "' is not one of the campaign's parameters");
    };
    rc.a = index_of(pair[0].get<std::string>(), 0);
    rc.b = index_of(pair[1].get<std::string>(), 1);
    if (rc.a == rc.b) c.fail("parameters", "must name two different parameters");
    rc.rho = c.number("rank");
    c.finish();
    spec.correlations.push_back(rc);
  }

}

CampaignSpec parse_campaign_spec(const std::string& json_text, const std::string& file_label,
                                 const std::string& base_dir) {
  const json root_json = input::parse_json_document(json_text, file_label);
  CampaignSpec spec;
  spec.file = file_label;
  Reader root(root_json, campaign_doc(), "", spec.file);
  spec.name = root.string("name");
  if (const std::string problem = campaign_name_problem(spec.name); !problem.empty()) root.fail("name", problem);
  spec.description = root.string("description");

  if (root.has("scene") == root.has("model"))
    root.fail(root.has("scene") ? "model" : "scene", "exactly one of scene (a scene file) and model (" +
                                                          std::string("ishigami|test") + ") is required");
  if (root.has("scene")) {
    const std::string scene = root.string("scene");
    spec.scene = resolve_scene(scene, base_dir);
    if (spec.scene.empty())
      root.fail("scene", "cannot open '" + scene + "' (looked in the current directory and next to the spec)");
  } else {
    spec.model = root.choice("model");
  }

  {
    const json& overrides = root.map("overrides");
    for (auto it = overrides.begin(); it != overrides.end(); ++it) spec.overrides.emplace_back(it.key(), it.value().dump());
  }

  spec.listed = root_json.contains("design") && root_json["design"].is_object() &&
                root_json["design"].contains("type") && root_json["design"]["type"] == "list";
  read_parameters(root, root_json, spec);

  if (spec.listed) {
    Reader d = root.object("design");
    d.accept("type");
    read_list_design(d, root_json["design"], spec, base_dir);
    d.finish();
  } else {
    if (!root.has("design")) root.fail("design", "is required (an object with type and samples)");
    Reader d = root.object("design");
    const std::vector<std::pair<const char*, DesignType>> types = {{"monte_carlo", DesignType::kMonteCarlo},
                                                                   {"lhs", DesignType::kLatinHypercube},
                                                                   {"sobol", DesignType::kSobol},
                                                                   {"grid", DesignType::kGrid},
                                                                   {"one_at_a_time", DesignType::kOneAtATime},
                                                                   {"saltelli", DesignType::kSaltelli},
                                                                   {"list", DesignType::kMonteCarlo}};
    spec.design.type = d.choice<DesignType>("type", types);
    const auto t = spec.design.type;
    const bool needs_samples = t == DesignType::kMonteCarlo || t == DesignType::kLatinHypercube ||
                               t == DesignType::kSobol || t == DesignType::kSaltelli ||
                               (t == DesignType::kGrid && !d.has("levels") &&
                                std::any_of(spec.parameters.begin(), spec.parameters.end(), [](const auto& p) {
                                  return p.distribution.type != sampling::DistributionType::kChoice;
                                }));
    if (needs_samples || d.has("samples"))
      spec.design.samples = static_cast<size_t>(d.integer("samples"));
    if (t == DesignType::kGrid || t == DesignType::kOneAtATime) {
      spec.design.levels = static_cast<size_t>(d.integer_or("levels", t == DesignType::kGrid ? 0 : 1,
                                                              std::pair<long long, long long>(t == DesignType::kGrid ? 2 : 1, 1000)));
    }
    if (t == DesignType::kSaltelli)
      spec.design.saltelli_base = d.choice<DesignType>("base",
                                                       {{"monte_carlo", DesignType::kMonteCarlo},
                                                        {"lhs", DesignType::kLatinHypercube},
                                                        {"sobol", DesignType::kSobol}});
    d.finish();
    const size_t n = sampling::design_size([&] {
      std::vector<Distribution> ds;
      for (const auto& p : spec.parameters) ds.push_back(p.distribution);
      return ds;
    }(), spec.design);
    if (n == 0) d.fail(t == DesignType::kGrid ? "levels" : "samples", "gives a design with no points");
    if (n > 10000000) d.fail("samples", "gives " + std::to_string(n) + " runs; at most 10000000 are allowed");
  }

  spec.seed = static_cast<std::uint64_t>(spec.listed ? root.integer_or("seed", 0) : root.integer("seed"));

  {
    Reader r = root.object("run");
    spec.run.time_limit_s = r.number("time_limit_s");
    spec.run.threads = static_cast<int>(r.integer("threads"));
    spec.run.memory_limit_mb = r.number("memory_limit_mb");
    spec.run.output_dir = r.string("output_dir");
    spec.run.checkpoint_every_s = r.number("checkpoint_every_s");
    if (spec.run.checkpoint_every_s > 0 && spec.run.checkpoint_every_s < 1)
      r.fail("checkpoint_every_s", "must be 0 (no checkpoints) or in [1, 1e7] wall-clock seconds");
    r.finish();
  }
  root.finish();

  // The campaign's identity: what decides the design and the results. `run` and `description` may change
  // between a job and its resume (a longer time limit, more threads).
  json identity = root_json;
  identity.erase("run");
  identity.erase("description");
  // A list design's labels only name its points in tables: renaming one changes no result.
  if (spec.listed)
    for (auto& point : identity["design"]["points"]) point.erase("label");
  spec.canonical = identity.dump();
  spec.hash = text_hash(spec.canonical);

  if (spec.listed) {
    validate_against_target(spec, spec.points);
    return spec;
  }
  std::vector<Distribution> dists;
  for (const auto& p : spec.parameters) dists.push_back(p.distribution);
  sampling::Design design;
  try {
    design = sampling::generate_design(dists, spec.correlations, spec.design, spec.seed);
  } catch (const std::exception& e) {
    throw InputError(spec.file, spec.correlations.empty() ? "design" : "correlation", e.what());
  }
  validate_against_target(spec, design);
  spec.points = std::move(design);
  return spec;
}

CampaignSpec parse_spec_parameters(const std::string& json_text, const std::string& file_label) {
  CampaignSpec spec;
  spec.file = file_label;
  const json root_json = input::parse_json_document(json_text, file_label);
  Reader root(root_json, campaign_doc(), "", spec.file);
  spec.listed = root_json.contains("design") && root_json["design"].is_object() &&
                root_json["design"].contains("type") && root_json["design"]["type"] == "list";
  if (root_json.contains("model") && root_json["model"].is_string()) spec.model = root_json["model"];
  read_parameters(root, root_json, spec);
  return spec;
}

CampaignSpec load_campaign_spec(const std::string& file) {
  const std::string dir = fs::path(file).parent_path().string();
  return parse_campaign_spec(input::read_input_file(file, input::JsonLimits{}.max_bytes, "campaign spec"), file, dir);
}

}  // namespace flume::campaigns
