#include "solver/run_output.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "common/version.h"

namespace flume {

std::string status_name(RunStatus s) {
  switch (s) {
    case RunStatus::kOk: return "ok";
    case RunStatus::kUnstable: return "unstable";
    case RunStatus::kKilled: return "killed";
    default: return "running";
  }
}

std::map<std::string, double> compute_metrics(const Scene& scene, const Record& record, double arrival_threshold_m) {
  std::map<std::string, double> m;
  for (const auto& [name, ts] : record.gauges) {
    const GaugeSummary g = summarize_gauge(ts.time, ts.values, arrival_threshold_m);
    if (g.has_peak) {
      m[name + ".peak_m"] = g.peak;
      m[name + ".peak_time_s"] = g.peak_time;
    }
    m[name + ".arrived"] = g.arrived ? 1.0 : 0.0;
    if (g.arrived) m[name + ".arrival_s"] = g.arrival_time;
  }
  for (const auto& [name, ts] : record.loads) {
    double peak = 0, peak_x = 0, impulse = 0;
    for (size_t i = 0; i < ts.size(); ++i) {
      double mag2 = 0;
      for (int c = 0; c < ts.components; ++c) mag2 += ts.at(i, c) * ts.at(i, c);
      peak = std::max(peak, std::sqrt(mag2));
      peak_x = std::max(peak_x, ts.at(i, 0));
      if (i > 0) impulse += ts.at(i, 0) * (ts.time[i] - ts.time[i - 1]);  // each sample is the interval's mean
    }
    m[name + ".peak_force_n"] = peak;
    m[name + ".peak_fx_n"] = peak_x;
    m[name + ".impulse_x_ns"] = impulse;
  }
  for (const auto& [name, ts] : record.pressures) {
    const PressureSummary p = summarize_pressure(ts.time, ts.values);
    m[name + ".peak_pressure_pa"] = p.peak;
    m[name + ".peak_pressure_time_s"] = p.peak_time;
    m[name + ".impulse_pa_s"] = p.impulse;
  }
  const auto& mass = record.diagnostics.at("mass");
  if (!mass.empty()) {
    m["mass_kg"] = mass.back();
    m["mass_relative_change"] = mass.front() > 0 ? (mass.back() - mass.front()) / mass.front() : 0.0;
  }
  (void)scene;
  return m;
}

void write_run_json(const std::string& path, RunStatus status, const std::string& message,
                    const std::map<std::string, double>& metrics, const Cost& cost, const Scene& scene) {
  nlohmann::json j;
  j["status"] = status_name(status);
  j["message"] = message;
  j["scene"] = scene.file;
  j["method"] = to_string(scene.solver.method);
  // The scene as it ran (overrides applied); parsed back, it is the scene file's JSON.
  if (!scene.source_json.empty()) j["scene_json"] = nlohmann::json::parse(scene.source_json);
  j["flume_version"] = build_info::version_and_commit();
  j["metrics"] = nlohmann::json::object();
  for (const auto& [k, v] : metrics)
    if (std::isfinite(v)) j["metrics"][k] = v;
  j["cost"] = {{"wall_s", cost.wall_s},
               {"steps", cost.steps},
               {"particles", cost.particles},
               {"particle_steps_per_s", cost.particle_steps_per_s},
               {"peak_rss_mb", cost.peak_rss_mb}};
  const std::string tmp = path + ".part";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
    if (!out) throw std::runtime_error(tmp + ": cannot write");
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace flume
