#include "study/tradeoff.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "calibration/records.h"
#include "campaigns/engine.h"
#include "campaigns/run_folders.h"
#include "common/command.h"
#include "common/errors.h"
#include "common/input/field_reader.h"
#include "common/input/json_input.h"
#include "common/plot/figure.h"
#include "solver/scene.h"
#include "store/h5/run_file.h"
#include "study/spec_fields.h"

namespace flume::study {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

std::string num(double v, int digits = 3) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}
std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// A campaign error speaks of `design.points.K...`; the study's author wrote `settings.K...`.
InputError as_study_error(const InputError& e, const std::string& file) {
  std::string field = e.field();
  const std::string from = "design.points";
  if (field.rfind(from, 0) == 0) field = "settings" + field.substr(from.size());
  if (field == "design") field = "settings";
  return InputError(file, field, e.problem());
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s.empty() ? std::string("none") : s;
}

// `outputs.metrics`: each entry a name (or pattern) string or {"name", "scale"}.
std::vector<MetricOutput> parse_metric_outputs(const nlohmann::json& a, const std::string& file) {
  const std::string what =
      "a run.json metric name (`*` matches any characters but '.') or "
      "{\"name\": NAME, \"scale\": number >= 0}";
  if (!a.is_array()) throw InputError(file, "outputs.metrics", "must be an array, each entry " + what);
  std::vector<MetricOutput> metrics;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string at = "outputs.metrics." + std::to_string(i);
    MetricOutput m;
    std::string name_field = at;
    if (a[i].is_string()) {
      m.name = a[i].get<std::string>();
    } else if (a[i].is_object()) {
      for (auto it = a[i].begin(); it != a[i].end(); ++it)
        if (it.key() != "name" && it.key() != "scale")
          throw InputError(file, at + "." + it.key(), "unknown field (known: name, scale)");
      name_field = at + ".name";
      if (!a[i].contains("name") || !a[i]["name"].is_string())
        throw InputError(file, name_field,
                         "is required: a run.json metric name (`*` matches any characters but '.')");
      m.name = a[i]["name"].get<std::string>();
      if (a[i].contains("scale")) {
        const json& v = a[i]["scale"];
        if (!v.is_number() || !(v.get<double>() >= 0) || !std::isfinite(v.get<double>()))
          throw InputError(file, at + ".scale",
                           "must be a number >= 0 in the metric's unit (the relative difference's least "
                           "denominator), got " +
                               v.dump());
        m.scale = v.get<double>();
      }
    } else {
      throw InputError(file, at, "must be " + what);
    }
    if (m.name.empty()) throw InputError(file, name_field, "must not be empty");
    for (size_t j = 0; j < metrics.size(); ++j)
      if (metrics[j].name == m.name)
        throw InputError(file, name_field,
                         "'" + m.name + "' is already outputs.metrics." + std::to_string(j));
    metrics.push_back(m);
  }
  return metrics;
}

}  // namespace

TradeoffSpec parse_tradeoff_spec(const std::string& json_text, const std::string& file_label,
                                 const std::string& base_dir) {
  TradeoffSpec spec;
  spec.file = file_label;
  auto fail = [&](const std::string& field, const std::string& what) -> InputError {
    return InputError(file_label, field, what);
  };
  const json root = input::parse_json_document(json_text, file_label);
  // Unknown fields are refused first, before anything runs; name, description, scene, overrides and run are read
  // by the campaign parser below (with the campaign's descriptions), outputs and reference here.
  input::FieldReader reader(root, study_doc(), "", file_label);
  for (const auto& f : study_doc().fields)
    if (reader.has(f.key)) reader.accept(f.key);
  reader.finish();
  if (!root.contains("settings") || !root["settings"].is_array() || root["settings"].size() < 2)
    throw fail("settings",
               "is required: an array of at least two settings {\"label\": ..., path: value, ...}");
  const json& settings = root["settings"];
  for (size_t i = 0; i < settings.size(); ++i) {
    const std::string at = "settings." + std::to_string(i);
    if (!settings[i].is_object()) throw fail(at, "must be an object {\"label\": ..., path: value, ...}");
    if (!settings[i].contains("label") || !settings[i]["label"].is_string() ||
        settings[i]["label"].get<std::string>().empty())
      throw fail(at + ".label", "is required: a non-empty string naming the setting in tables and plots");
    spec.labels.push_back(settings[i]["label"].get<std::string>());
  }

  // The runs: a campaign whose design is the list of settings.
  json campaign = {{"design", {{"type", "list"}, {"points", settings}}}};
  for (const char* key : {"name", "description", "scene", "overrides", "run"})
    if (root.contains(key)) campaign[key] = root[key];
  try {
    spec.campaign = campaigns::parse_campaign_spec(campaign.dump(), file_label, base_dir);
  } catch (const InputError& e) {
    throw as_study_error(e, file_label);
  }

  // What the base scene offers, for the outputs' names and the default window.
  std::vector<Override> fixed_sets;
  for (const auto& [path, value] : spec.campaign.overrides) fixed_sets.push_back({path, value});
  const Scene scene = load_scene(spec.campaign.scene, fixed_sets);
  std::vector<std::string> scene_gauges, scene_loads;
  for (const auto& g : scene.instruments.gauges) scene_gauges.push_back(g.name);
  for (const auto& l : scene.instruments.loads) scene_loads.push_back(l.name);

  static const json no_outputs = json::object();
  const json& outputs = root.contains("outputs") ? root["outputs"] : no_outputs;
  input::FieldReader out(outputs, study_outputs_doc(), "outputs", file_label);
  for (const auto& f : study_outputs_doc().fields)
    if (out.has(f.key)) out.accept(f.key);
  out.finish();
  auto names = [&](const char* key, const std::vector<std::string>& allowed, std::vector<std::string>& out,
                   bool all_by_default) {
    if (!outputs.contains(key)) {
      if (all_by_default) out = allowed;
      return;
    }
    const json& a = outputs[key];
    if (!a.is_array())
      throw fail(std::string("outputs.") + key, "must be an array of names (" + joined(allowed) + ")");
    for (size_t i = 0; i < a.size(); ++i) {
      const std::string field = std::string("outputs.") + key + "." + std::to_string(i);
      if (!a[i].is_string()) throw fail(field, "must be a name (" + joined(allowed) + ")");
      const std::string n = a[i].get<std::string>();
      if (std::find(allowed.begin(), allowed.end(), n) == allowed.end())
        throw fail(field, "'" + n + "' is not in the scene (it has: " + joined(allowed) + ")");
      out.push_back(n);
    }
  };
  names("gauges", scene_gauges, spec.gauges, true);
  spec.scene_gauges = scene_gauges;
  names("loads", scene_loads, spec.loads, true);
  if (outputs.contains("metrics")) spec.metrics = parse_metric_outputs(outputs["metrics"], file_label);
  if (spec.gauges.empty() && spec.loads.empty() && spec.metrics.empty())
    throw fail("outputs", "names no gauge, no load cell and no metric to compare (the scene has gauges: " +
                              joined(scene_gauges) + "; loads: " + joined(scene_loads) +
                              "; metrics: any name of run.json's `metrics`)");
  spec.window_start_s = 0;
  spec.window_end_s = scene.solver.end_time;
  if (outputs.contains("window_s")) {
    const json& w = outputs["window_s"];
    if (!w.is_array() || w.size() != 2 || !w[0].is_number() || !w[1].is_number() ||
        !(w[0].get<double>() >= 0) || !(w[1].get<double>() > w[0].get<double>()))
      throw fail("outputs.window_s", "must be [t0, t1] with 0 <= t0 < t1 (s), got " + w.dump());
    spec.window_start_s = w[0].get<double>();
    spec.window_end_s = w[1].get<double>();
  }
  spec.arrival_threshold_m = out.number("arrival_threshold_m");
  spec.front_s = out.number("front_s", input::Bounds{0.0, spec.window_end_s - spec.window_start_s});

  if (!root.contains("reference") || !root["reference"].is_object() || root["reference"].size() != 1)
    throw fail("reference",
               "is required: {\"setting\": LABEL} (one of the settings) or {\"records\": CSV file}");
  input::FieldReader ref = reader.object("reference");
  if (ref.has("setting")) {
    const std::string label = ref.string("setting");
    const auto it = std::find(spec.labels.begin(), spec.labels.end(), label);
    if (it == spec.labels.end())
      throw fail("reference.setting", "'" + label + "' is not the label of any setting");
    spec.reference_setting = static_cast<size_t>(it - spec.labels.begin());
  } else if (ref.has("records")) {
    fs::path p(ref.string("records"));
    if (!p.is_absolute() && !fs::exists(p) && !base_dir.empty()) p = fs::path(base_dir) / p;
    spec.reference_records = p.string();
    if (!outputs.contains("loads")) spec.loads.clear();  // a gauge record: gauges only unless asked
    if (!spec.loads.empty())
      throw fail("outputs.loads", "a measured gauge record has no loads to compare: list gauges only");
    if (!spec.metrics.empty())
      throw fail("outputs.metrics",
                 "a measured gauge record has no run metrics to compare: take a setting as the reference");
    // Checked now, so a study does not run for an hour before finding its record unreadable.
    std::set<std::string> have;
    for (const auto& rec :
         calibration::read_target_csv(spec.reference_records, {}, spec.scene_gauges, spec.window_start_s,
                                      spec.window_end_s, 1.0, "reference.records"))
      have.insert(rec.gauge);
    for (size_t i = 0; i < spec.gauges.size(); ++i)
      if (!have.count(spec.gauges[i]))
        throw fail(
            "outputs.gauges." + std::to_string(i),
            "'" + spec.gauges[i] + "' has no column in the reference record " + spec.reference_records);
  }
  ref.finish();
  return spec;
}

TradeoffSpec load_tradeoff_spec(const std::string& file) {
  return parse_tradeoff_spec(input::read_input_file(file, input::JsonLimits{}.max_bytes, "study spec"), file,
                             fs::path(file).parent_path().string());
}

namespace {

Series read_gauge(const std::string& h5, const std::string& name) {
  Series s;
  s.time = h5::read_vector(h5, "/gauges/" + name + "/time");
  s.value = h5::read_vector(h5, "/gauges/" + name + "/elevation");
  return s;
}

// Peak magnitude of a load cell's force in the window.
double load_peak(const std::string& h5, const std::string& name, double t0, double t1) {
  h5::Reader r(h5);
  const auto t = r.read_vector("/loads/" + name + "/time");
  const auto f = r.read_vector("/loads/" + name + "/force");
  const size_t cols = t.empty() ? 1 : f.size() / t.size();
  double peak = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t0 || t[i] > t1) continue;
    double m2 = 0;
    for (size_t c = 0; c < cols; ++c) m2 += f[i * cols + c] * f[i * cols + c];
    if (std::isfinite(m2)) peak = std::max(peak, std::sqrt(m2));
  }
  return peak;
}

std::string changes_of(const campaigns::CampaignSpec& c, size_t k) {
  std::string s;
  for (size_t j = 0; j < c.parameters.size(); ++j) {
    if (!campaigns::has_value(c, k, j)) continue;
    std::string v = campaigns::value_json(c.parameters[j], c.points.values[k][j]);
    const json value = json::parse(v);
    if (value.is_string())
      v = c.parameters[j].path == campaigns::kScenePath ? fs::path(value.get<std::string>()).stem().string()
                                                        : value.get<std::string>();
    else
      v = num(value.get<double>(), 6);  // 2e+07, not 20000000.0
    s += (s.empty() ? "" : ", ") + c.parameters[j].path + "=" + v;
  }
  return s.empty() ? "(scene as is)" : s;
}

// A run's run.json: its cost into `r`; returns its `metrics` object (empty where there is no run.json or it
// is unreadable: a run killed while writing it, whose cost stays unknown).
json read_run_json(const std::string& run_dir, SettingResult& r) {
  std::ifstream in(fs::path(run_dir) / "run.json");
  if (!in) return json::object();
  try {
    const json j = json::parse(in);
    const json& cost = j.at("cost");
    r.steps = cost.value("steps", -1LL);
    r.particles = cost.value("particles", -1LL);
    r.peak_rss_mb = cost.value("peak_rss_mb", NAN);
    if (r.steps >= 0 && r.particles >= 0) r.particle_steps = double(r.steps) * double(r.particles);
    const auto metrics = j.find("metrics");
    return metrics != j.end() && metrics->is_object() ? *metrics : json::object();
  } catch (const std::exception&) {
    return json::object();
  }
}

MetricReading metric_reading(const json& metrics, const std::string& name) {
  MetricReading m;
  const auto it = metrics.find(name);
  if (it == metrics.end()) return m;
  m.present = true;
  if (it->is_number()) m.value = it->get<double>();  // null or a string: present, not finite
  return m;
}

}  // namespace

TradeoffResult evaluate_tradeoff(const TradeoffSpec& spec, const std::string& db_file) {
  const auto& c = spec.campaign;
  store::CampaignStore db(db_file, true);
  const auto campaign = db.find_campaign(c.name);
  if (!campaign) throw InputError(db_file, "", "no campaign named '" + c.name + "' (run the study first)");
  const auto planned = campaigns::plan_runs(c);
  TradeoffResult result;
  std::vector<std::string> h5(planned.size());
  std::vector<json> run_metrics(planned.size(), json::object());
  // A run has a result once it ended ok, with its result file where gauges or load cells are compared (the
  // metrics are in run.json).
  const bool needs_h5 = !spec.gauges.empty() || !spec.loads.empty();
  std::vector<bool> has_result(planned.size(), false);
  for (size_t k = 0; k < planned.size(); ++k) {
    SettingResult r;
    r.label = spec.labels[k];
    r.changes = changes_of(c, k);
    r.reference = spec.reference_setting && *spec.reference_setting == k;
    const auto stored = db.find_run(campaign->id, planned[k].param_hash);
    if (stored) {
      r.run_id = stored->id;
      r.status = stored->status;
      r.message = stored->message;
      r.wall_s = stored->wall_s;
      if (r.status == store::RunStatus::kOk && !stored->h5_path.empty() && fs::exists(stored->h5_path))
        h5[k] = stored->h5_path;
      has_result[k] = r.status == store::RunStatus::kOk && (!needs_h5 || !h5[k].empty());
      run_metrics[k] = read_run_json(stored->run_dir, r);
    }
    result.rows.push_back(r);
  }

  // The reference's series.
  std::map<std::string, Series> ref_gauges;
  std::map<std::string, double> ref_loads;
  if (spec.reference_setting) {
    const size_t k = *spec.reference_setting;
    const auto& r = result.rows[k];
    if (!has_result[k])
      throw InputError(spec.file, "reference.setting",
                       "the reference '" + r.label + "' has no result (status " + store::to_string(r.status) +
                           (r.message.empty() ? "" : ": " + r.message) + "); errors need it");
    for (const auto& g : spec.gauges) ref_gauges[g] = read_gauge(h5[k], g);
    for (const auto& l : spec.loads)
      ref_loads[l] = load_peak(h5[k], l, spec.window_start_s, spec.window_end_s);
    result.reference = "setting '" + r.label + "' (" + r.changes + ")";
  } else {
    for (const auto& rec :
         calibration::read_target_csv(spec.reference_records, {}, spec.scene_gauges, spec.window_start_s,
                                      spec.window_end_s, 1.0, "reference.records"))
      ref_gauges[rec.gauge] = {rec.time, rec.elevation};
    result.reference = "measured record " + spec.reference_records;
  }
  // The reference's metrics (parse_tradeoff_spec allows metrics with a reference setting only), which the
  // patterns are expanded against.
  const json no_metrics = json::object();
  const json& ref_metrics = spec.reference_setting ? run_metrics[*spec.reference_setting] : no_metrics;
  if (!spec.metrics.empty()) {
    std::vector<std::string> ref_names;
    for (auto it = ref_metrics.begin(); it != ref_metrics.end(); ++it) ref_names.push_back(it.key());
    std::vector<size_t> unmatched;
    result.metrics = expand_metric_patterns(spec.metrics, ref_names, &unmatched);
    if (!unmatched.empty()) {
      const size_t i = unmatched.front();
      throw InputError(spec.file, "outputs.metrics." + std::to_string(i),
                       "'" + spec.metrics[i].name +
                           "' matches none of the reference run's metrics (it has: " + joined(ref_names) +
                           ")");
    }
  }
  result.measured[kRms] = result.measured[kArrival] = !spec.gauges.empty();
  result.measured[kPeak] = !spec.gauges.empty() || !spec.loads.empty();
  result.measured[kMetric] = !result.metrics.empty();

  std::vector<double> cost;
  std::vector<double> errors[kMeasureCount];
  for (size_t k = 0; k < result.rows.size(); ++k) {
    auto& r = result.rows[k];
    if (has_result[k]) {
      // The gauge and load-cell aggregates: means over what is finite.
      double sum[kMeasureCount] = {};
      int n[kMeasureCount] = {};
      auto add = [&](int m, double v) {
        if (std::isfinite(v)) sum[m] += v, ++n[m];
      };
      for (const auto& g : spec.gauges) {
        const Series sim = read_gauge(h5[k], g);
        const Series& ref = ref_gauges.at(g);
        GaugeError e =
            compare_gauge(g, sim, ref, spec.window_start_s, spec.window_end_s, spec.arrival_threshold_m);
        if (spec.front_s > 0) {
          // The RMS around the reference's front only; where it never arrived, over the whole window.
          const double a = e.ref_arrival_s;
          if (std::isfinite(a)) {
            e.rms_m = rms_difference(sim, ref, std::max(spec.window_start_s, a - spec.front_s / 4),
                                     std::min(spec.window_end_s, a + spec.front_s));
            e.rms_rel = e.rms_m / std::fabs(e.ref_peak_m);
          }
        }
        add(kRms, e.rms_rel);
        add(kPeak, std::fabs(e.peak_rel));
        if (std::isfinite(e.arrival_diff_s))
          add(kArrival, std::fabs(e.arrival_diff_s));
        else if (std::isfinite(e.arrival_s) != std::isfinite(e.ref_arrival_s))
          add(kArrival, spec.window_end_s - (std::isfinite(e.arrival_s) ? e.arrival_s : e.ref_arrival_s));
        else if (!std::isfinite(e.arrival_s))
          add(kArrival, 0.0);  // neither arrived: they agree
        r.gauges.push_back(e);
      }
      for (const auto& l : spec.loads) {
        LoadError e{l, load_peak(h5[k], l, spec.window_start_s, spec.window_end_s), ref_loads.at(l), 0};
        e.peak_rel = (e.peak_n - e.ref_peak_n) / std::fabs(e.ref_peak_n);
        r.loads.push_back(e);
        add(kPeak, std::fabs(e.peak_rel));
      }
      for (int m : {kRms, kPeak, kArrival}) r.error[m] = n[m] ? sum[m] / n[m] : NAN;
      for (const auto& m : result.metrics)
        r.metrics.push_back(
            compare_metric(m, metric_reading(run_metrics[k], m.name), metric_reading(ref_metrics, m.name)));
      r.error[kMetric] = mean_metric_error(r.metrics);
    }
    // The reference setting is exact by definition: it is shown, not ranked.
    cost.push_back(r.reference ? NAN : r.wall_s);
    for (int m = 0; m < kMeasureCount; ++m) errors[m].push_back(r.reference ? NAN : r.error[m]);
  }
  for (int m = 0; m < kMeasureCount; ++m) {
    const auto front = pareto_front(cost, errors[m]);
    for (size_t k = 0; k < front.size(); ++k) result.rows[k].pareto[m] = front[k];
  }
  return result;
}

void store_errors(const TradeoffResult& result, const std::string& db_file) {
  store::CampaignStore db(db_file);
  for (const auto& r : result.rows) {
    if (r.run_id == 0 || r.status != store::RunStatus::kOk) continue;
    std::vector<std::pair<std::string, double>> m;
    for (int k = 0; k < kMeasureCount; ++k) {
      if (!result.measured[k]) continue;
      const std::string name = std::string("error.") + kErrorNames[k] + (k == kArrival ? "_s" : "");
      m.emplace_back(name, r.reference ? 0.0 : r.error[k]);
      m.emplace_back(std::string("pareto.") + kErrorNames[k], r.pareto[k] ? 1.0 : 0.0);
    }
    for (const auto& g : r.gauges) {
      m.emplace_back("error." + g.name + ".rms_m", g.rms_m);
      m.emplace_back("error." + g.name + ".peak_rel", g.peak_rel);
      m.emplace_back("error." + g.name + ".arrival_diff_s", g.arrival_diff_s);
    }
    for (const auto& l : r.loads) m.emplace_back("error." + l.name + ".peak_rel", l.peak_rel);
    for (const auto& e : r.metrics) {
      m.emplace_back("error." + e.name + ".diff", e.diff);
      m.emplace_back("error." + e.name + ".rel", e.rel);
    }
    db.record_metrics(r.run_id, m);  // leaves out what is not finite (a missing metric's difference)
  }
}

std::string tradeoff_markdown(const TradeoffSpec& spec, const TradeoffResult& result) {
  std::ostringstream md;
  md << "Errors against the " << result.reference << ", over t = " << num(spec.window_start_s) << " to "
     << num(spec.window_end_s) << " s"
     << (spec.front_s > 0 ? ", RMS from " + num(spec.front_s / 4) + " s before to " + num(spec.front_s) +
                                " s after the reference's arrival at each gauge"
                          : std::string())
     << ". `rms`: mean over gauges of RMS(difference) / reference peak; `peak`: mean of |peak error| / "
        "reference peak (gauges and load cells); `arrival`: mean |arrival difference| (s; where only one "
        "arrived, the time from its arrival to the window's end); `metric`: mean over the run metrics of "
        "|value - reference| / max(|reference|, scale). Pareto: the settings on the front of that error "
        "against wall time.\n\n";
  md << "| setting | changes | status | wall s | particle-steps | peak RSS MB | rms | peak | arrival s | "
        "metric | Pareto |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : result.rows) {
    std::string front;
    for (int m = 0; m < kMeasureCount; ++m)
      if (r.pareto[m]) front += (front.empty() ? "" : ", ") + std::string(kErrorNames[m]);
    md << "| " << r.label << (r.reference ? " (reference)" : "") << " | " << r.changes << " | "
       << store::to_string(r.status) << " | " << fixed(r.wall_s, 1) << " | " << num(r.particle_steps) << " | "
       << fixed(r.peak_rss_mb, 0);
    for (int m = 0; m < kMeasureCount; ++m)
      md << " | " << (!result.measured[m] ? "-" : r.reference ? "0" : num(r.error[m], 2));
    md << " | " << front << " |\n";
  }
  if (!spec.gauges.empty()) {
    md << "\nPer gauge: RMS error (mm) / peak error (%) / arrival difference (s)\n\n| setting |";
    for (const auto& g : spec.gauges) md << " " << g << " |";
    md << "\n|---|";
    for (size_t i = 0; i < spec.gauges.size(); ++i) md << "---|";
    md << "\n";
    for (const auto& r : result.rows) {
      if (r.gauges.empty() || r.reference) continue;
      md << "| " << r.label << " |";
      for (const auto& g : r.gauges)
        md << " " << fixed(1e3 * g.rms_m, 1) << " / " << fixed(100 * g.peak_rel, 0) << " / "
           << (std::isfinite(g.arrival_diff_s)
                   ? fixed(g.arrival_diff_s, 2)
                   : std::string(std::isfinite(g.arrival_s) || std::isfinite(g.ref_arrival_s) ? "one arrived"
                                                                                              : "-"))
           << " |";
      md << "\n";
    }
  }
  if (!spec.loads.empty()) {
    md << "\nPer load cell: peak force (N) / its error (%)\n\n| setting |";
    for (const auto& l : spec.loads) md << " " << l << " |";
    md << "\n|---|";
    for (size_t i = 0; i < spec.loads.size(); ++i) md << "---|";
    md << "\n";
    for (const auto& r : result.rows) {
      if (r.loads.empty()) continue;
      md << "| " << r.label << " |";
      for (const auto& l : r.loads) md << " " << num(l.peak_n) << " / " << fixed(100 * l.peak_rel, 0) << " |";
      md << "\n";
    }
  }
  if (!result.metrics.empty()) {
    md << "\nPer run metric: value / difference / relative difference (%), the relative difference being "
          "|value - reference| / max(|reference|, scale); a metric the reference lacks (or has as 0 with "
          "scale 0) is left out of `metric`, and a run that lacks one the reference has gets no `metric`\n\n"
          "| setting |";
    for (const auto& m : result.metrics) md << " " << m.name << " |";
    md << "\n|---|";
    for (size_t i = 0; i < result.metrics.size(); ++i) md << "---|";
    md << "\n| scale |";
    for (const auto& m : result.metrics) md << " " << num(m.scale) << " |";
    md << "\n";
    for (const auto& r : result.rows) {
      if (r.metrics.empty()) continue;
      md << "| " << r.label << (r.reference ? " (reference)" : "") << " |";
      for (const auto& e : r.metrics) {
        const std::string own = reading_problem(e.value);
        md << " ";
        if (!own.empty())
          md << own;
        else if (r.reference)
          md << num(e.value.value, 4);
        else
          md << num(e.value.value, 4) << " / " << num(e.diff, 2) << " / "
             << (std::isfinite(e.rel) ? fixed(100 * e.rel, 1) : metric_problem(e));
        md << " |";
      }
      md << "\n";
    }
  }
  bool any_failed = false;
  for (const auto& r : result.rows)
    if (r.status != store::RunStatus::kOk) {
      if (!any_failed) md << "\nRuns without a result:\n\n";
      any_failed = true;
      md << "- " << r.label << ": " << store::to_string(r.status)
         << (r.message.empty() ? "" : ": " + r.message) << "\n";
    }
  return md.str();
}

void write_tradeoff(const TradeoffSpec& spec, const TradeoffResult& result, const std::string& out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir, "--out", "cannot create the output directory: " + ec.message());
  {
    std::ofstream md(fs::path(out_dir) / "tradeoff.md");
    md << "# Trade-off study '" << spec.campaign.name << "'\n\n"
       << tradeoff_markdown(spec, result) << "\n![error against wall time](tradeoff.svg)\n";
    if (!md) throw InputError(out_dir, "--out", "cannot write tradeoff.md");
  }
  {
    std::ofstream csv(fs::path(out_dir) / "tradeoff.csv");
    auto q = [](const std::string& s) {
      std::string o = "\"";
      for (char ch : s) o += ch == '"' ? std::string("\"\"") : std::string(1, ch);
      return o + "\"";
    };
    auto v = [](double x) { return std::isfinite(x) ? num(x, 10) : std::string(); };
    csv << "label,changes,status,reference,wall_s,steps,particles,particle_steps,peak_rss_mb,error_rms,error_"
           "peak,error_arrival_s,error_metric,pareto_rms,pareto_peak,pareto_arrival,pareto_metric";
    for (const auto& g : spec.gauges)
      csv << "," << g << ".rms_m," << g << ".peak_m," << g << ".peak_rel," << g << ".arrival_s," << g
          << ".arrival_diff_s";
    for (const auto& l : spec.loads) csv << "," << l << ".peak_n," << l << ".peak_rel";
    for (const auto& m : result.metrics)
      csv << "," << m.name << ".value," << m.name << ".diff," << m.name << ".rel," << m.name << ".problem";
    csv << "\n";
    for (const auto& r : result.rows) {
      csv << q(r.label) << "," << q(r.changes) << "," << store::to_string(r.status) << "," << r.reference
          << "," << v(r.wall_s) << "," << (r.steps >= 0 ? std::to_string(r.steps) : "") << ","
          << (r.particles >= 0 ? std::to_string(r.particles) : "") << "," << v(r.particle_steps) << ","
          << v(r.peak_rss_mb) << "," << v(r.error[kRms]) << "," << v(r.error[kPeak]) << ","
          << v(r.error[kArrival]) << "," << v(r.error[kMetric]) << "," << r.pareto[kRms] << ","
          << r.pareto[kPeak] << "," << r.pareto[kArrival] << "," << r.pareto[kMetric];
      for (size_t i = 0; i < spec.gauges.size(); ++i) {
        if (i < r.gauges.size()) {
          const auto& g = r.gauges[i];
          csv << "," << v(g.rms_m) << "," << v(g.peak_m) << "," << v(g.peak_rel) << "," << v(g.arrival_s)
              << "," << v(g.arrival_diff_s);
        } else {
          csv << ",,,,,";
        }
      }
      for (size_t i = 0; i < spec.loads.size(); ++i) {
        if (i < r.loads.size())
          csv << "," << v(r.loads[i].peak_n) << "," << v(r.loads[i].peak_rel);
        else
          csv << ",,";
      }
      for (size_t i = 0; i < result.metrics.size(); ++i) {
        if (i < r.metrics.size()) {
          const auto& e = r.metrics[i];
          csv << "," << v(e.value.value) << "," << v(e.diff) << "," << v(e.rel) << ","
              << q(metric_problem(e));
        } else {
          csv << ",,,,";
        }
      }
      csv << "\n";
    }
    if (!csv) throw InputError(out_dir, "--out", "cannot write tradeoff.csv");
  }
  // Each error against wall time, on log axes; the front joined and ringed. One panel per error the spec has
  // outputs for (a study of debris metrics alone would otherwise show three empty panels).
  std::vector<int> drawn;
  for (int m = 0; m < kMeasureCount; ++m)
    if (result.measured[m]) drawn.push_back(m);
  const int panels = static_cast<int>(drawn.size());
  plot::Figure fig(1, panels, 500 * panels, 500);
  fig.title("'" + spec.campaign.name + "': error against cost (vs " + result.reference + ")");
  static const char* kYLabels[kMeasureCount] = {"RMS error / ref. peak", "|peak error| / ref. peak",
                                                "|arrival error| [s]",
                                                "mean |metric diff.| / max(|ref.|, scale)"};
  for (int panel = 0; panel < panels; ++panel) {
    const int m = drawn[panel];
    auto& ax = fig.axes(0, panel);
    ax.xlabel("wall time [s]")
        .ylabel(kYLabels[m])
        .xscale(plot::Scale::kLog)
        .yscale(plot::Scale::kLog)
        .grid(true);
    std::vector<double> x, y, fx, fy;
    std::vector<std::pair<double, double>> front;
    for (const auto& r : result.rows) {
      // A zero error has no place on a log axis: it is in the table.
      if (r.reference || !(r.wall_s > 0) || !std::isfinite(r.wall_s) || !(r.error[m] > 0) ||
          !std::isfinite(r.error[m]))
        continue;
      x.push_back(r.wall_s);
      y.push_back(r.error[m]);
      if (r.pareto[m]) front.emplace_back(r.wall_s, r.error[m]);
    }
    if (x.empty()) continue;
    std::sort(front.begin(), front.end());
    for (const auto& [a, b] : front) fx.push_back(a), fy.push_back(b);
    plot::MarkerStyle all;
    all.label = "settings";
    all.size = 7;
    ax.scatter(x, y, all);
    plot::LineStyle line;
    line.label = "Pareto front";
    line.dash = plot::Dash::kDashed;
    ax.line(fx, fy, line);
    plot::MarkerStyle ring;
    ring.marker = plot::Marker::kDiamond;
    ring.size = 12;
    ring.opacity = 0.6;
    ax.scatter(fx, fy, ring);
    for (const auto& r : result.rows)
      if (!r.reference && r.error[m] > 0 && std::isfinite(r.error[m]) && r.wall_s > 0) {
        plot::TextStyle t;
        t.size = 9;
        ax.text(r.wall_s * 1.06, r.error[m], r.label, t);
      }
    ax.legend(plot::Legend::kUpperRight);
  }
  fig.save((fs::path(out_dir) / "tradeoff.svg").string());
}

void add_study_command(CLI::App& app) {
  struct Args {
    std::string spec, db, out;
    int workers = 1;
  };
  auto a = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "tradeoff",
      "runs (or resumes) every setting as a campaign in FILE, then writes DIR/tradeoff.{md,csv,svg}: error against "
      "cost over fidelity settings, Pareto front");
  sub->add_option("SPEC", a->spec, "the study spec (docs/tradeoff.md)")->required();
  sub->add_option("--db", a->db, "the campaign database")->required();
  sub->add_option("--out", a->out, "the folder for tradeoff.{md,csv,svg} (default: FILE.study/<name>)");
  sub->add_option("--workers", a->workers, "runs at a time")->check(CLI::Range(1, 4096));
  cli::on_parse(*sub, [a]() -> int {
    const std::string& spec_file = a->spec;
    const std::string& db = a->db;
    const int workers = a->workers;
    std::string out = a->out;
    const TradeoffSpec spec = load_tradeoff_spec(spec_file);
    if (out.empty()) out = (fs::path(db + ".study") / spec.campaign.name).string();
    campaigns::check_writable_folder(out, out, "--out");  // before the campaign runs, not after
    campaigns::EngineOptions opt;
    opt.db_file = db;
    opt.local_workers = workers;
    opt.terminal = isatty(STDERR_FILENO);
    const int rc = campaigns::run_campaign(spec.campaign, opt, 1);
    if (rc != kExitOk) return rc;
    const TradeoffResult result = evaluate_tradeoff(spec, db);
    store_errors(result, db);
    write_tradeoff(spec, result, out);
    std::printf("%s\nwrote %s/tradeoff.{md,csv,svg}\n", tradeoff_markdown(spec, result).c_str(), out.c_str());
    return kExitOk;
  });
}

}  // namespace flume::study
