// Analytic models, run as their own process like the solver so the campaign engine cannot tell them apart.
#include "campaigns/models.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
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
      {"gauge", gauge_model_inputs()},  // also reservoir.forcing.table.<i>.<0|1> (gauge_model.h)
  };
  return models;
}

const std::vector<std::string> kBehaviours = {"ok", "segfault", "hang", "unstable", "fail"};

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
    } else if (!v.is_number() || !std::isfinite(v.get<double>())) {
      return name + ": must be a finite number (got " + v.dump() + ")";
    } else if (name == "sleep_s" && !(v.get<double>() >= 0 && v.get<double>() <= 3600)) {
      return name + ": must be in [0, 3600] (got " + v.dump() + ")";
    }
  }
  return "";
}

int model_main(int argc, char** argv) {
  const char* usage = "usage: flume model ishigami|test --out DIR [--set name=value ...]\n";
  if (argc < 2) {
    std::fputs(usage, stderr);
    return kExitInvalidInput;
  }
  const std::string model = argv[1];
  std::string out_dir;
  std::vector<std::pair<std::string, std::string>> sets;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      out_dir = argv[++i];
    } else if (a == "--set" && i + 1 < argc) {
      const std::string s = argv[++i];
      const auto eq = s.find('=');
      if (eq == std::string::npos || eq == 0) {
        std::fprintf(stderr, "--set: %s: expected name=value\n", s.c_str());
        return kExitInvalidInput;
      }
      sets.emplace_back(s.substr(0, eq), s.substr(eq + 1));
    } else if (a == "--threads" && i + 1 < argc) {
      ++i;  // accepted for symmetry with `flume run`; the models are serial
    } else {
      std::fprintf(stderr, "flume model: unknown argument '%s'\n%s", a.c_str(), usage);
      return kExitInvalidInput;
    }
  }
  if (out_dir.empty()) {
    std::fprintf(stderr, "flume model: --out DIR is required\n");
    return kExitInvalidInput;
  }
  const std::string problem = check_model_inputs(model, sets);
  if (!problem.empty()) {
    std::fprintf(stderr, "--set: %s\n", problem.c_str());
    return kExitInvalidInput;
  }
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
