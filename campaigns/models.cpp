// Analytic models, run as their own process like the solver so the campaign engine cannot tell them apart.
#include "campaigns/models.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <nlohmann/json.hpp>
#include <thread>

#include "campaigns/gauge_model.h"
#include "common/errors.h"

namespace flume::campaigns {
namespace {

using json = nlohmann::json;

const std::map<std::string, std::vector<std::string>>& registry() {
  static const std::map<std::string, std::vector<std::string>> models = {
      {"ishigami", {"x1", "x2", "x3"}},
      {"test", {"x", "y", "z", "behaviour", "sleep_s"}},
      {"debris", {"friction", "restitution", "n_debris", "wave_scale", "obstacles.layout"}},
      {"gauge", gauge_model_inputs()},  // also reservoir.forcing.table.<i>.<0|1> (gauge_model.h)
  };
  return models;
}

const std::vector<std::string> kBehaviours = {"ok", "segfault", "hang", "unstable", "fail"};
const std::vector<std::string> kLayouts = {"0x0", "5x1", "5x2"};

json parse_value(const std::string& text) {
  try {
    return json::parse(text);
  } catch (const json::parse_error&) {
    return text;  // as `flume run --set`: what is not JSON is a string
  }
}

struct ModelInput {
  std::map<std::string, json> values;
  double number(const std::string& name, double def) const {
    auto it = values.find(name);
    return it == values.end() ? def : it->second.get<double>();
  }
};

void write_run_json(const std::string& dir, const json& j) {
  // Written to a temporary name and renamed, so a reader never sees half a file.
  const std::string tmp = dir + "/run.json.part";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
  }
  std::filesystem::rename(tmp, dir + "/run.json");
}


// SYNTHETIC STAND-IN, NOT PHYSICS: plausible debris metrics (the solver's D<k>.* contract) from friction,
// restitution, debris count, obstacle layout and a wave scale, so the report's spreading section can be
// exercised before the coupled solver exists. Median run-up displacement follows Nistor et al. (2017)
// eq. 58 scaled by (0.35 / friction)^0.5, spreading angles scale with eq. 59 and the restitution; the
// scatter between debris is a fixed function of the inputs (the same inputs give the same metrics).
json debris_metrics(const ModelInput& in) {
  const double mu = in.number("friction", 0.35), e = in.number("restitution", 0.3);
  const double scale = in.number("wave_scale", 1.0);
  const int n = static_cast<int>(in.number("n_debris", 6));
  const std::string layout = in.values.count("obstacles.layout") ? in.values.at("obstacles.layout").get<std::string>() : "0x0";
  const int rows = layout == "5x2" ? 2 : layout == "5x1" ? 1 : 0;
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a of the inputs seeds the debris-to-debris scatter
  for (const auto& [name, v] : in.values)
    for (unsigned char c : name + "=" + v.dump()) h = (h ^ c) * 1099511628211ull;
  std::mt19937_64 rng(h);
  std::normal_distribution<double> z(0.0, 1.0);

  const double x_quay = 4.45, x_end = 9.0, col = 0.10, pitch = 0.325, row_dx = 0.45, x_row0 = 5.11;
  const double median_long = scale * (3.58 - 0.09 * n) * std::sqrt(0.35 / mu) * (1.0 - 0.18 * rows);
  const double theta_scale = (3.69 + 0.80 * n) * (0.4 + e) * 0.6;
  json m = json::object();
  int dammed_count = 0;
  for (int k = 0; k < n; ++k) {
    const double x0 = 4.68, y0 = 1.79 + 0.21 * (k % 3);  // Waseda slots: 3 across, a second layer on top
    double x_run = x0 + std::min(median_long * std::exp(0.12 * z(rng)), x_end - 0.05 - x0);
    const double theta = ((y0 - 2.0) / 0.21 * 0.5 + z(rng)) * theta_scale * M_PI / 180.0;
    auto y_at = [&](double x) { return std::clamp(y0 + (x - x0) * std::tan(theta), 0.05, 3.95); };
    bool dammed = false;
    for (int r = 0; r < rows && !dammed; ++r) {
      const double xf = x_row0 + row_dx * r;
      if (x_run <= xf) break;
      for (int c = 0; c < 5; ++c)
        if (std::abs(y_at(xf) - (2.0 + (c - 2) * pitch)) < col / 2 + 0.01) {
          x_run = xf - 0.03;
          dammed = true;
          break;
        }
    }
    const double y_run = y_at(x_run);
    const double back = dammed ? 0.0 : (x_run - x0) * std::clamp(0.15 + 0.3 * (0.5 - mu), 0.0, 0.5);
    const double x_rest = std::max(x_run - back, x_quay + 0.05);
    const double y_rest = std::clamp(y_run + 0.2 * (y_run - y0) + 0.03 * z(rng), 0.05, 3.95);
    const std::string p = "D" + std::to_string(k + 1) + ".";
    const double lon_max = x_run - x0, lon_rest = x_rest - x0;
    m[p + "initial_x_m"] = x0;
    m[p + "initial_y_m"] = y0;
    m[p + "runup_x_m"] = x_run;
    m[p + "runup_y_m"] = y_run;
    m[p + "rest_x_m"] = x_rest;
    m[p + "rest_y_m"] = y_rest;
    m[p + "longitudinal_max_m"] = lon_max;
    m[p + "longitudinal_rest_m"] = lon_rest;
    m[p + "lateral_runup_m"] = y_run - y0;
    m[p + "lateral_rest_m"] = y_rest - y0;
    m[p + "spreading_runup_deg"] = std::atan2(y_run - y0, std::max(lon_max, 1e-3)) * 180.0 / M_PI;
    m[p + "spreading_rest_deg"] = std::atan2(y_rest - y0, std::max(lon_rest, 1e-3)) * 180.0 / M_PI;
    m[p + "dammed"] = dammed ? 1.0 : 0.0;
    const double accel = scale * (3.0 + (dammed ? 12.0 : 0.0)) * std::exp(0.2 * z(rng));  // m/s^2
    m[p + "accel_peak_force_n"] = 0.226 * accel;
    m[p + "accel_peak_force_30hz_n"] = 0.226 * accel * 0.6;
    dammed_count += dammed;
  }
  m["LC1.peak_force_n"] = rows > 0 ? scale * (4.0 + 6.0 * dammed_count) : 0.0;
  m["LC1.impulse_x_ns"] = rows > 0 ? scale * (1.5 + 0.8 * dammed_count) : 0.0;
  m["WG3.peak_m"] = 0.065 * scale;
  m["WG3.arrival_s"] = 3.9 / std::sqrt(scale);
  return m;
}


}  // namespace

std::vector<std::string> model_inputs(const std::string& model) {
  auto it = registry().find(model);
  return it == registry().end() ? std::vector<std::string>{} : it->second;
}

std::vector<std::string> model_names() {
  std::vector<std::string> out;
  for (const auto& [name, inputs] : registry()) out.push_back(name);
  return out;
}

std::string check_model_inputs(const std::string& model,
                               const std::vector<std::pair<std::string, std::string>>& inputs) {
  const auto names = model_inputs(model);
  if (names.empty()) return "model: unknown model '" + model + "'";
  if (model == "gauge") return check_gauge_inputs(inputs);
  for (const auto& [name, text] : inputs) {
    if (std::find(names.begin(), names.end(), name) == names.end()) {
      std::string allowed;
      for (const auto& n : names) allowed += (allowed.empty() ? "" : ", ") + n;
      return name + ": not an input of model " + model + " (its inputs: " + allowed + ")";
    }
    const json v = parse_value(text);
    if (name == "behaviour") {
      if (!v.is_string() || std::find(kBehaviours.begin(), kBehaviours.end(), v.get<std::string>()) == kBehaviours.end())
        return name + ": must be one of ok|segfault|hang|unstable|fail (got " + v.dump() + ")";
    } else if (name == "obstacles.layout") {
      if (!v.is_string() || std::find(kLayouts.begin(), kLayouts.end(), v.get<std::string>()) == kLayouts.end())
        return name + ": must be one of 0x0|5x1|5x2 (got " + v.dump() + ")";
    } else if (!v.is_number() || !std::isfinite(v.get<double>())) {
      return name + ": must be a finite number (got " + v.dump() + ")";
    } else if (name == "sleep_s" && !(v.get<double>() >= 0 && v.get<double>() <= 3600)) {
      return name + ": must be in [0, 3600] (got " + v.dump() + ")";
    } else if (name == "friction" && !(v.get<double>() >= 0.05 && v.get<double>() <= 1.5)) {
      return name + ": must be in [0.05, 1.5] (got " + v.dump() + ")";
    } else if (name == "restitution" && !(v.get<double>() >= 0 && v.get<double>() <= 1)) {
      return name + ": must be in [0, 1] (got " + v.dump() + ")";
    } else if (name == "n_debris" && v.get<double>() != 3 && v.get<double>() != 6) {
      return name + ": must be 3 or 6 (got " + v.dump() + ")";
    } else if (name == "wave_scale" && !(v.get<double>() >= 0.1 && v.get<double>() <= 3)) {
      return name + ": must be in [0.1, 3] (got " + v.dump() + ")";
    }
  }
  return "";
}

int run_model(const std::string& model, const std::string& out_dir,
              const std::vector<std::pair<std::string, std::string>>& sets) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  ModelInput in;
  for (const auto& [name, text] : sets) in.values[name] = parse_value(text);

  const auto t0 = std::chrono::steady_clock::now();
  json result = {{"status", "ok"}, {"message", ""}};
  int code = kExitOk;
  if (model == "gauge") {
    std::map<std::string, double> metrics;
    std::int64_t steps = 0;
    run_gauge_model(sets, out_dir, metrics, steps);
    result["metrics"] = metrics;
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    result["cost"] = {{"wall_s", wall_s}, {"steps", steps}, {"particles", 0}, {"particle_steps_per_s", 0.0},
                      {"peak_rss_mb", 0.0}};
    write_run_json(out_dir, result);
    return kExitOk;
  }
  if (model == "ishigami") {
    const double a = 7.0, b = 0.1;
    const double x1 = in.number("x1", 0), x2 = in.number("x2", 0), x3 = in.number("x3", 0);
    const double s2 = std::sin(x2);
    result["metrics"] = {{"y", std::sin(x1) + a * s2 * s2 + b * std::pow(x3, 4) * std::sin(x1)}};
  } else if (model == "debris") {
    result["metrics"] = debris_metrics(in);
  } else {
    const double sleep_s = in.number("sleep_s", 0);
    const std::string behaviour = in.values.count("behaviour") ? in.values["behaviour"].get<std::string>() : "ok";
    if (sleep_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(sleep_s));
    if (behaviour == "segfault") {
      std::raise(SIGSEGV);  // a crash as the solver would have one: no run.json, killed by a signal
    } else if (behaviour == "hang") {
      for (;;) pause();
    }
    result["metrics"] = {{"y", in.number("x", 0) + 10 * in.number("y", 0) + 100 * in.number("z", 0)}};
    if (behaviour == "unstable") {
      result["status"] = "unstable";
      result["message"] = "CFL exceeded: max particle speed 1e3 m/s at t = 0.1 s (test model)";
      code = kExitUnstable;
    } else if (behaviour == "fail") {
      result["status"] = "failed";
      result["message"] = "internal error requested by the test model";
      code = kExitInternal;
    }
  }
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  result["cost"] = {{"wall_s", wall_s}, {"steps", 1}, {"particles", 0}, {"particle_steps_per_s", 0.0},
                    {"peak_rss_mb", 0.0}};
  write_run_json(out_dir, result);
  if (code != kExitOk) std::fprintf(stderr, "%s\n", result["message"].get<std::string>().c_str());
  return code;
}

}  // namespace flume::campaigns
