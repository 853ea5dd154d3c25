// Calibration spec JSON -> CalibrationSpec, checked once here (fields, ranges, scene paths, target records).
#include "calibration/spec.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "calibration/objective.h"
#include "calibration/spec_fields.h"
#include "campaigns/gauge_model.h"
#include "campaigns/run_folders.h"
#include "campaigns/spec.h"
#include "common/errors.h"
#include "common/input/field_reader.h"
#include "common/input/json_input.h"
#include "solver/scene.h"

namespace flume::calibration {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
constexpr double kInf = std::numeric_limits<double>::infinity();

using input::type_name;

using Reader = input::FieldReader;
using input::Bounds;

struct AlgorithmInfo {
  const char* name;
  bool local;
};
// The names the spec accepts; optimize.cpp maps each to its NLopt algorithm.
const std::vector<AlgorithmInfo>& algorithms() {
  static const std::vector<AlgorithmInfo> list = {{"BOBYQA", true}, {"COBYLA", true},   {"NELDERMEAD", true},
                                                  {"SBPLX", true},  {"CRS2_LM", false}, {"DIRECT_L", false},
                                                  {"ISRES", false}, {"MLSL", false}};
  return list;
}


std::string resolve(const std::string& path, const std::string& base_dir) {
  fs::path p(path);
  std::error_code ec;
  if (p.is_absolute()) return p.lexically_normal().string();
  if (fs::exists(p, ec)) return fs::absolute(p, ec).lexically_normal().string();
  if (!base_dir.empty() && fs::exists(fs::path(base_dir) / p, ec))
    return fs::absolute(fs::path(base_dir) / p, ec).lexically_normal().string();
  return "";
}

// Deterministic start points in the unit cube: a Halton sequence (bases 2, 3, 5, ...) shifted by a
// seed-derived offset modulo 1 (Cranley & Patterson 1976), so starts spread evenly and reproducibly.
std::vector<std::vector<double>> halton_points(size_t count, size_t dim, std::uint64_t seed) {
  static const int primes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71};
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ull;
  auto splitmix = [&] {
    std::uint64_t x = (z += 0x9e3779b97f4a7c15ull);
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return static_cast<double>((x ^ (x >> 31)) >> 11) * 0x1.0p-53;
  };
  std::vector<double> shift(dim);
  for (auto& s : shift) s = splitmix();
  std::vector<std::vector<double>> out;
  for (size_t i = 1; i <= count; ++i) {
    std::vector<double> p(dim);
    for (size_t d = 0; d < dim; ++d) {
      const int b = primes[d % 20];
      double f = 1, r = 0;
      for (size_t n = i; n > 0; n /= b) {
        f /= b;
        r += f * static_cast<double>(n % b);
      }
      p[d] = std::fmod(r + shift[d], 1.0);
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace

double FreeParameter::to_unit(double value) const {
  if (scale == Scale::kLog) return std::log(value / lower) / std::log(upper / lower);
  return (value - lower) / (upper - lower);
}

double FreeParameter::from_unit(double u) const {
  u = std::clamp(u, 0.0, 1.0);
  if (scale == Scale::kLog) return lower * std::pow(upper / lower, u);
  return lower + u * (upper - lower);
}

size_t CalibrationSpec::run_parameter_count() const {
  return static_cast<size_t>(std::count_if(parameters.begin(), parameters.end(),
                                           [](const FreeParameter& p) { return p.needs_run; }));
}

std::vector<std::string> algorithm_names() {
  std::vector<std::string> out;
  for (const auto& a : algorithms()) out.push_back(a.name);
  return out;
}

bool is_local_algorithm(const std::string& name) {
  for (const auto& a : algorithms())
    if (name == a.name) return a.local;
  return false;
}

CalibrationSpec parse_calibration_spec(const std::string& json_text, const std::string& file_label,
                                       const std::string& base_dir) {
  const json root_json = input::parse_json_document(json_text, file_label);
  CalibrationSpec spec;
  spec.file = file_label;
  Reader root(root_json, calibration_doc(), "", spec.file);
  json identity = json::object();  // what the results depend on; see CalibrationSpec::canonical

  spec.name = root.string("name");
  if (const std::string problem = campaigns::campaign_name_problem(spec.name); !problem.empty()) root.fail("name", problem);
  identity["name"] = spec.name;
  spec.description = root.string("description");

  // The simulator: a scene (default the Waseda 2D slice) or the `gauge` test stand-in.
  if (root.has("scene") && root.has("model")) root.fail("model", "give either scene or model, not both");
  if (root.has("model")) {
    spec.model = root.choice("model");
    identity["model"] = spec.model;
  } else {
    const std::string scene = root.string("scene");
    spec.scene = resolve(scene, base_dir);
    if (spec.scene.empty())
      root.fail("scene",
                "cannot open '" + scene + "' (looked in the current directory and next to the spec)");
    identity["scene"] = spec.scene;
    identity["scene_content"] =
        campaigns::text_hash(read_scene_file(spec.scene));  // an edited scene is a new scene
  }

  {
    const json& overrides = root.map("overrides");
    for (auto it = overrides.begin(); it != overrides.end(); ++it) spec.overrides.emplace_back(it.key(), it.value().dump());
    identity["overrides"] = root_json.value("overrides", json::object());
  }

  // Free parameters.
  auto params = root.objects("parameters");
  if (params.empty())
    root.fail("parameters", "is required: a non-empty array of {path, lower, upper, start}");
  std::set<std::string> paths;
  for (auto& p : params) {
    FreeParameter fp;
    fp.path = p.string("path");
    if (fp.path.empty()) p.fail("path", "must not be empty");
    if (fp.path == kTimeShiftPath) p.fail("path", "the time shift is set with objective.time_shift");
    if (!paths.insert(fp.path).second) p.fail("path", "'" + fp.path + "' is already a free parameter");
    for (const auto& [path, value] : spec.overrides)
      if (path == fp.path) p.fail("path", "'" + fp.path + "' is also a fixed override");
    fp.scale = p.choice("scale") == "log" ? Scale::kLog : Scale::kLinear;
    fp.lower = p.number("lower", Bounds{fp.scale == Scale::kLog ? 0.0 : -kInf, kInf, fp.scale == Scale::kLog});
    fp.upper = p.number("upper", Bounds{fp.lower, kInf, true});
    fp.start = p.number("start", Bounds{fp.lower, fp.upper});
    p.finish();
    spec.parameters.push_back(fp);
  }
  identity["parameters"] = root_json["parameters"];

  // Objective.
  {
    if (!root.has("objective"))
      root.fail("objective", "is required (an object with window [t0, t1] at least)");
    Reader o = root.object("objective");
    const json& w = o.array("window");
    if (w.size() != 2 || !w[0].is_number() || !w[1].is_number() || !(w[0].get<double>() >= 0) ||
        !(w[1].get<double>() > w[0].get<double>()))
      o.fail("window", "is required: [t0, t1] in s with 0 <= t0 < t1");
    spec.objective.window_start_s = w[0].get<double>();
    spec.objective.window_end_s = w[1].get<double>();
    spec.objective.peak_weight = o.number("peak_weight");
    spec.objective.arrival_weight_m_per_s = o.number("arrival_weight_m_per_s");
    spec.objective.arrival_threshold_m = o.number("arrival_threshold_m");
    const json& stages = o.array("stages");
    if (stages.size() > 16)
      o.fail("stages", "takes at most 16 end times (got " + std::to_string(stages.size()) + ")");
    for (const json& end : stages) {
      const double t0 = spec.objective.window_start_s, t1 = spec.objective.window_end_s;
      const double before = spec.objective.stage_end_s.empty() ? t0 : spec.objective.stage_end_s.back();
      if (!end.is_number() || !(end.get<double>() > before) || !(end.get<double>() < t1))
        o.fail("stages", "must be increasing end times in s, each inside the window (" +
                             input::number_text(t0) + ", " + input::number_text(t1) + ") (got " + end.dump() +
                             ")");
      spec.objective.stage_end_s.push_back(end.get<double>());
    }
    if (o.has("time_shift")) {
      Reader s = o.object("time_shift");
      FreeParameter fp;
      fp.path = kTimeShiftPath;
      fp.needs_run = false;
      fp.lower = s.number("lower");
      fp.upper = s.number("upper", Bounds{fp.lower, 60.0, true});
      fp.start = s.number("start", Bounds{fp.lower, fp.upper});
      s.finish();
      spec.parameters.push_back(fp);
    }
    o.finish();
    identity["objective"] = root_json["objective"];
  }

  // Algorithm and budgets.
  {
    if (!root.has("algorithm"))
      root.fail("algorithm", "is required (an object with name and max_evaluations)");
    Reader a = root.object("algorithm");
    auto& al = spec.algorithm;
    al.name = a.choice("name");
    if (al.name == "MLSL") {
      al.local = a.choice("local");
    } else if (a.has("local")) {
      a.fail("local", "is MLSL's local optimizer; " + al.name + " takes none");
    }
    if (a.has("polish")) {
      if (is_local_algorithm(al.name))
        a.fail("polish", "follows a global algorithm; " + al.name + " is local");
      al.polish = a.choice("polish");
    }
    if (!a.has("max_evaluations")) a.fail("max_evaluations", "is required (an integer in [1, 1000000], per start)");
    al.max_evaluations = static_cast<int>(a.integer("max_evaluations"));
    al.polish_evaluations = static_cast<int>(a.integer("polish_evaluations"));
    al.max_time_s = a.number("max_time_s");
    al.xtol_abs = a.number("xtol_abs");
    al.ftol_abs = a.number("ftol_abs");
    al.initial_step = a.number("initial_step");
    al.stage_step = a.number("stage_step");
    if (!spec.objective.stage_end_s.empty() && !is_local_algorithm(al.name))
      a.fail("name",
             "is global; objective.stages refines each stage's optimum and needs a local algorithm "
             "(BOBYQA, COBYLA, NELDERMEAD or SBPLX)");
    al.population = static_cast<int>(a.integer("population"));
    al.seed = static_cast<std::uint64_t>(a.integer("seed"));
    a.finish();
    const size_t dim = spec.parameters.size();
    if ((al.name == "BOBYQA" || al.polish == "BOBYQA" || al.local == "BOBYQA") && dim < 2)
      a.fail(al.name == "BOBYQA" ? "name" : (al.polish == "BOBYQA" ? "polish" : "local"),
             "BOBYQA needs at least 2 free parameters (NLopt); use SBPLX or COBYLA for one");
    json id = root_json["algorithm"];
    id.erase("max_evaluations");  // budgets: see AlgorithmSpec
    id.erase("polish_evaluations");
    id.erase("max_time_s");
    identity["algorithm"] = id;
  }

  // Starts: the parameters' own, explicit ones, and quasi-random ones.
  {
    std::vector<double> first;
    for (const auto& p : spec.parameters) first.push_back(p.start);
    spec.starts.push_back(first);
    // A start's fields are the free parameters, each within its bounds, defaulting to its own start.
    input::ObjectDoc start_doc{"starts[]", "", {}};
    for (const auto& p : spec.parameters)
      start_doc.fields.push_back(input::number(p.path, "start value").def(p.start).in(p.lower, p.upper));
    const json& starts = root.array("starts");
    for (size_t i = 0; i < starts.size(); ++i) {
      Reader s(starts[i], start_doc, "starts." + std::to_string(i), spec.file);
      std::vector<double> x;
      for (const auto& p : spec.parameters) x.push_back(s.number(p.path));
      s.finish();
      spec.starts.push_back(x);
    }
    if (root.has("multi_start")) {
      Reader m = root.object("multi_start");
      const auto count = static_cast<size_t>(m.integer("random"));
      const auto seed = static_cast<std::uint64_t>(m.integer("seed"));
      m.finish();
      for (const auto& u : halton_points(count, spec.parameters.size(), seed)) {
        std::vector<double> x;
        for (size_t j = 0; j < u.size(); ++j) x.push_back(spec.parameters[j].from_unit(u[j]));
        spec.starts.push_back(x);
      }
    }
    identity["starts"] = root_json.value("starts", json::array());
    identity["multi_start"] = root_json.value("multi_start", json::object());
  }

  {
    Reader p = root.object("profile");
    spec.profile.points = static_cast<int>(p.integer("points"));
    spec.profile.span = p.number("span");
    p.finish();
  }
  {
    Reader r = root.object("run");
    spec.run.time_limit_s = r.number("time_limit_s");
    spec.run.threads = static_cast<int>(r.integer("threads"));
    spec.run.output_dir = r.string("output_dir");
    r.finish();
  }

  // Targets need the objective window and the simulator's gauges, so the simulator is checked first.
  auto targets = root.objects("targets");
  root.finish();
  if (targets.empty()) root.fail("targets", "is required: a non-empty array of {file, gauges?, weight?}");

  // The simulator accepts the overrides and each parameter at its bounds and start; which gauges it has.
  auto sets_with = [&](size_t j, double value) {
    std::vector<std::pair<std::string, std::string>> sets = spec.overrides;
    sets.emplace_back(spec.parameters[j].path, json(value).dump());
    return sets;
  };
  if (!spec.model.empty()) {
    std::string problem = campaigns::check_gauge_inputs(spec.overrides);
    if (!problem.empty())
      throw InputError(spec.file, "overrides." + problem.substr(0, problem.find(':')),
                       problem.substr(problem.find(": ") + 2));
    for (size_t j = 0; j < spec.parameters.size(); ++j) {
      if (!spec.parameters[j].needs_run) continue;
      for (double v : {spec.parameters[j].lower, spec.parameters[j].upper, spec.parameters[j].start}) {
        problem = campaigns::check_gauge_inputs(sets_with(j, v));
        if (!problem.empty())
          throw InputError(spec.file, "parameters." + std::to_string(j),
                           "model gauge rejects " + spec.parameters[j].path + " = " + input::number_text(v) +
                               ": " + problem);
      }
    }
    spec.gauges = campaigns::gauge_model_gauges();
    spec.record_end_s = campaigns::gauge_model_end_time(spec.overrides);
  } else {
    const std::string text = read_scene_file(spec.scene);
    auto load = [&](const std::vector<std::pair<std::string, std::string>>& sets) {
      std::vector<Override> o;
      for (const auto& [path, value] : sets) o.push_back({path, value});
      return parse_scene_text(text, spec.scene, o);
    };
    Scene scene;
    try {
      scene = load(spec.overrides);
    } catch (const InputError& e) {
      throw InputError(spec.file, "overrides", "the scene rejects them: " + std::string(e.what()));
    }
    for (size_t j = 0; j < spec.parameters.size(); ++j) {
      if (!spec.parameters[j].needs_run) continue;
      for (double v : {spec.parameters[j].lower, spec.parameters[j].upper, spec.parameters[j].start}) {
        try {
          load(sets_with(j, v));
        } catch (const InputError& e) {
          throw InputError(spec.file, "parameters." + std::to_string(j),
                           "the scene rejects " + spec.parameters[j].path + " = " + input::number_text(v) +
                               ": " + e.what());
        }
      }
    }
    for (const auto& g : scene.instruments.gauges) spec.gauges.push_back(g.name);
    spec.record_end_s = scene.solver.end_time;
  }
  // The shifted simulation must cover the window: sim(t - shift) for t up to the window's end.
  double max_back_shift = 0;
  for (const auto& p : spec.parameters)
    if (!p.needs_run) max_back_shift = std::min(0.0, p.lower);
  if (spec.record_end_s < spec.objective.window_end_s - max_back_shift)
    throw InputError(spec.file, "objective.window",
                     "ends at " + input::number_text(spec.objective.window_end_s) +
                         " s but the simulation records only to " + input::number_text(spec.record_end_s) +
                         " s (solver.end_time" +
                         (max_back_shift < 0 ? ", with the time shift's lower bound" : std::string()) +
                         "); shorten the window or set solver.end_time in overrides");

  std::set<std::string> fitted;
  json target_ids = json::array();
  for (size_t i = 0; i < targets.size(); ++i) {
    const std::string field = "targets." + std::to_string(i);
    Reader& t = targets[i];
    TargetFile tf;
    const std::string file = t.string("file");
    tf.file = resolve(file, base_dir);
    if (tf.file.empty())
      t.fail("file", "cannot open '" + file + "' (looked in the current directory and next to the spec)");
    tf.weight = t.number("weight");
    if (t.has("gauge") && t.has("gauges"))
      t.fail("gauges", "give gauge (one column) or gauges (a map), not both");
    if (t.has("gauge")) {
      tf.gauge_columns.emplace_back(t.string("gauge"), "");
    } else if (t.has("gauges")) {
      const json& gauges = t.map("gauges");
      for (auto it = gauges.begin(); it != gauges.end(); ++it) {
        if (!it.value().is_string()) t.fail("gauges." + it.key(), "must be the name of a column of " + file);
        tf.gauge_columns.emplace_back(it.key(), it.value().get<std::string>());
      }
      if (tf.gauge_columns.empty()) t.fail("gauges", "maps no gauge");
    }
    t.finish();
    std::string gauge_list;
    for (const auto& g : spec.gauges) gauge_list += (gauge_list.empty() ? "" : ", ") + g;
    for (const auto& [gauge, column] : tf.gauge_columns)
      if (std::find(spec.gauges.begin(), spec.gauges.end(), gauge) == spec.gauges.end())
        t.fail(t.has("gauge") ? "gauge" : "gauges." + gauge, "'" + gauge + "' is not a gauge of the " +
                                                                 (spec.model.empty() ? "scene" : "model") +
                                                                 " (its gauges: " + gauge_list + ")");
    for (auto& r : read_target_csv(tf.file, tf.gauge_columns, spec.gauges, spec.objective.window_start_s,
                                   spec.objective.window_end_s, tf.weight, field)) {
      if (!fitted.insert(r.gauge).second)
        t.fail("file", "gauge " + r.gauge + " already has a target record; give each gauge one");
      spec.targets.push_back(std::move(r));
    }
    spec.target_files.push_back(tf);
    target_ids.push_back(
        {{"file", tf.file}, {"content", campaigns::text_hash(read_target_text(tf.file, "targets." + std::to_string(i)))}, {"spec", root_json["targets"][i]}});
  }
  identity["targets"] = target_ids;
  Objective check(spec.objective, spec.targets,
                  spec.file);  // targets without an arrival, when one is weighted
  for (double end : spec.objective.stage_end_s) {
    try {
      Objective stage(stage_objective(spec.objective, end), spec.targets, spec.file);
    } catch (const InputError& e) {
      throw InputError(spec.file, "objective.stages",
                       "the stage ending at " + input::number_text(end) + " s: " + e.problem());
    }
  }

  spec.canonical = identity.dump();
  spec.hash = campaigns::text_hash(spec.canonical);
  return spec;
}

CalibrationSpec load_calibration_spec(const std::string& file) {
  return parse_calibration_spec(input::read_input_file(file, input::JsonLimits{}.max_bytes, "calibration spec"), file,
                                fs::path(file).parent_path().string());
}

}  // namespace flume::calibration
