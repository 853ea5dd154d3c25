#include "calibration/report.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "common/plot/figure.h"

namespace flume::calibration {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json terms(const ObjectiveTerms& t) {
  json g = json::object();
  for (const auto& [name, gt] : t.gauges)
    g[name] = {{"rms_m", gt.rms_m},
               {"peak_error_m", gt.peak_error_m},
               {"arrival_error_s", gt.arrival_error_s},
               {"samples", gt.samples}};
  json j = {{"objective", num(t.value)},
            {"rms_m", num(t.rms_m)},
            {"peak_error_m", num(t.peak_error_m)},
            {"arrival_error_s", num(t.arrival_error_s)},
            {"gauges", g}};
  if (t.failed) j["failed"] = t.failure;
  return j;
}

json values(const CalibrationSpec& spec, const std::vector<double>& v) {
  json j = json::object();
  for (size_t k = 0; k < v.size() && k < spec.parameters.size(); ++k) j[spec.parameters[k].path] = v[k];
  return j;
}

void write_json(const std::string& file, const json& j) {
  const std::string tmp = file + ".part";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
    if (!out) throw std::runtime_error(tmp + ": cannot write");
  }
  fs::rename(tmp, file);
}

}  // namespace

void write_report(const CalibrationSpec& spec, const CalibrateOptions& options, const Objective& objective,
                  const CalibrationResult& result, const std::vector<store::Evaluation>& history) {
  fs::create_directories(options.out_dir);
  const fs::path out(options.out_dir);
  namespace plot = flume::plot;

  // fit.svg: one panel per gauge: target (markers), start 0's first evaluation (dashed) and fitted (line).
  {
    const int n = static_cast<int>(objective.windows().size());
    plot::Figure fig(n, 1, 720, 300.0 * n);
    fig.title("Calibration '" + spec.name + "': fitted and target records");
    for (int i = 0; i < n; ++i) {
      const auto& w = objective.windows()[static_cast<size_t>(i)];
      auto& ax = fig.axes(i, 0);
      ax.title(w.gauge).xlabel("t [s]").ylabel("elevation above still water [m]");
      ax.scatter(w.time, w.target,
                 {.color = plot::Color{0, 0, 0}, .size = 2.5, .opacity = 0.6, .label = "target"});
      auto clip = [&](const SimRecord& r, std::vector<double>& t, std::vector<double>& e) {
        for (size_t k = 0; k < r.time.size(); ++k)
          if (r.time[k] >= w.time.front() && r.time[k] <= w.time.back()) {
            t.push_back(r.time[k]);
            e.push_back(r.elevation[k]);
          }
      };
      if (auto it = result.start_records.find(w.gauge); it != result.start_records.end()) {
        std::vector<double> t, e;
        clip(it->second, t, e);
        ax.line(t, e,
                {.color = plot::palette(1),
                 .width = 1.2,
                 .dash = plot::Dash::kDashed,
                 .label = "first evaluation"});
      }
      if (auto it = result.best_records.find(w.gauge); it != result.best_records.end()) {
        std::vector<double> t, e;
        clip(it->second, t, e);
        ax.line(t, e, {.color = plot::palette(0), .width = 2.0, .label = "fitted"});
      }
      ax.legend(plot::Legend::kUpperRight);
    }
    fig.save((out / "fit.svg").string());
  }

  // fit.csv: target and fitted at the target's times.
  {
    std::ofstream csv(out / "fit.csv");
    csv << "gauge,time_s,target_m,fitted_m\n";
    csv.precision(10);
    for (const auto& w : objective.windows()) {
      auto it = result.best_records.find(w.gauge);
      for (size_t k = 0; k < w.time.size(); ++k)
        csv << w.gauge << "," << w.time[k] << "," << w.target[k] << ","
            << (it == result.best_records.end()
                    ? NAN
                    : interpolate(it->second.time, it->second.elevation, w.time[k]))
            << "\n";
    }
  }

  // profiles.svg: the objective along each parameter through the optimum.
  if (!result.profiles.empty()) {
    const int n = static_cast<int>(result.profiles.size());
    const int cols = std::min(n, 3), rows = (n + cols - 1) / cols;
    plot::Figure fig(rows, cols);
    fig.title("Objective along each parameter through the optimum");
    for (int i = 0; i < n; ++i) {
      const auto& p = result.profiles[static_cast<size_t>(i)];
      auto& ax = fig.axes(i / cols, i % cols);
      ax.title(p.path).xlabel(p.path).ylabel("objective [m]");
      ax.line(p.values, p.objective, {.color = plot::palette(0)});
      ax.scatter(p.values, p.objective, {.color = plot::palette(0), .size = 5});
      ax.vline(result.best[static_cast<size_t>(i)], {.dash = plot::Dash::kDashed, .label = "optimum"});
    }
    fig.save((out / "profiles.svg").string());
  }

  // history.svg: the whole window's objective per evaluation, one line per start (a window continuation's
  // stages, then optimize, then polish).
  {
    plot::Figure fig(1, 1, 640, 400);
    auto& ax = fig.axes().title("Objective per evaluation").xlabel("evaluation").ylabel("objective [m]");
    ax.yscale(plot::Scale::kLog);
    std::map<std::int64_t, std::pair<std::vector<double>, std::vector<double>>> lines;
    std::vector<std::string> phases;
    for (size_t k = 0; k < spec.objective.stage_end_s.size(); ++k) phases.push_back(stage_phase(k));
    phases.insert(phases.end(), {"optimize", "polish"});
    for (const auto& phase : phases)
      for (const auto& e : history)
        if (e.phase == phase && std::isfinite(e.value) && e.value > 0) {
          auto& [x, y] = lines[e.start];
          x.push_back(static_cast<double>(x.size() + 1));
          y.push_back(e.value);
        }
    for (const auto& [s, xy] : lines)
      ax.line(xy.first, xy.second,
              {.color = plot::palette(static_cast<size_t>(s)), .label = "start " + std::to_string(s)});
    if (!lines.empty()) {
      ax.legend(plot::Legend::kUpperRight);
      fig.save((out / "history.svg").string());
    }
  }

  json j;
  j["name"] = spec.name;
  j["spec"] = spec.file;
  j["status"] = result.status;
  j["simulator"] = spec.model.empty() ? json{{"scene", spec.scene}} : json{{"model", spec.model}};
  j["overrides"] = json::object();
  for (const auto& [path, value] : spec.overrides) j["overrides"][path] = json::parse(value);
  j["algorithm"] = {{"name", spec.algorithm.name},
                    {"local", spec.algorithm.local},
                    {"polish", spec.algorithm.polish},
                    {"max_evaluations", spec.algorithm.max_evaluations},
                    {"xtol_abs", spec.algorithm.xtol_abs}};
  j["best"] = {{"parameters", values(spec, result.best)},
               {"start", result.best_start},
               {"run", result.best_run},
               {"run_dir", result.best_run_dir},
               {"terms", terms(result.best_terms)}};
  j["objective"] = {{"window_s", {spec.objective.window_start_s, spec.objective.window_end_s}},
                    {"peak_weight", spec.objective.peak_weight},
                    {"arrival_weight_m_per_s", spec.objective.arrival_weight_m_per_s},
                    {"arrival_threshold_m", spec.objective.arrival_threshold_m},
                    {"stages_end_s", spec.objective.stage_end_s}};
  j["starts"] = json::array();
  for (const auto& s : result.starts)
    j["starts"].push_back({{"index", s.index},
                           {"from", values(spec, s.from)},
                           {"to", values(spec, s.best)},
                           {"objective", num(s.value)},
                           {"stage_evaluations", s.stage_evaluations},
                           {"evaluations", s.evaluations},
                           {"polish_evaluations", s.polish_evaluations},
                           {"stop", s.stop},
                           {"same_optimum", s.same_optimum}});
  j["profiles"] = json::object();
  for (const auto& p : result.profiles)
    j["profiles"][p.path] = {{"values", p.values},
                             {"objective", p.objective},
                             {"rise_low", num(p.rise_low)},
                             {"rise_high", num(p.rise_high)}};
  const auto& id = result.identifiability;
  j["identifiability"] = {{"available", id.available},
                          {"note", id.note},
                          {"samples", id.samples},
                          {"condition_number", num(id.condition_number)},
                          {"eigenvalues", id.eigenvalues}};
  if (id.available) {
    j["identifiability"]["std_error"] = values(spec, id.std_error);
    j["identifiability"]["correlation"] = id.correlation;
    j["identifiability"]["parameters"] = json::array();
    for (const auto& p : spec.parameters) j["identifiability"]["parameters"].push_back(p.path);
  }
  j["evaluations"] = {{"optimizer", result.optimizer_evaluations},
                      {"profile", result.profile_evaluations},
                      {"runs_in_store", result.runs_total},
                      {"runs_executed_now", result.runs_executed},
                      {"runs_read_back", result.runs_reused}};
  j["cost"] = {{"run_wall_s_mean", result.run_wall_s_mean},
               {"run_wall_s_total", result.run_wall_s_total},
               {"calibration_wall_s", result.wall_s}};
  j["targets"] = json::array();
  for (const auto& t : spec.targets)
    j["targets"].push_back(
        {{"gauge", t.gauge}, {"file", t.file}, {"column", t.column}, {"weight", t.weight}});
  j["files"] = {
      {"fit", "fit.svg"}, {"fit_csv", "fit.csv"}, {"profiles", "profiles.svg"}, {"history", "history.svg"}};
  j["database"] = options.db_file;
  write_json((out / "calibration.json").string(), j);
}

}  // namespace flume::calibration
