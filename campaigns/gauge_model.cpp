// The `gauge` test stand-in (gauge_model.h). Every number here is a stand-in choice, not a flume property.
#include "campaigns/gauge_model.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include "store/h5/run_file.h"

namespace flume::campaigns {
namespace {

using json = nlohmann::json;

json parse_value(const std::string& text) {
  try {
    return json::parse(text);
  } catch (const json::parse_error&) {
    return text;  // as `flume run --set`: what is not JSON is a string
  }
}
struct GaugeInputs {
  std::string forcing = "exponential";
  double t99_s = 0.8;
  std::vector<std::array<double, 2>> table = {{0.0, 1.0}, {0.3, 0.75}, {0.6, 0.4}, {0.9, 0.15}, {1.2, 0.0}};
  double gate_height_m = 0.10;
  double fill_level_m = 0.90;
  double still_water_m = 0.23;
  double end_time = 6.0;
  double undulation_m = 0.0;
  double sleep_s = 0.0;
};

std::string gauge_fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Applies the inputs in order (a whole table before its elements, as `flume run --set` does) and checks
// them. Returns "" or "<name>: <problem>".
std::string read_gauge_inputs(const std::vector<std::pair<std::string, std::string>>& inputs,
                              GaugeInputs& g) {
  static const std::regex element(R"(reservoir\.forcing\.table\.([0-9]+)\.([0-9]+))");
  auto number_in = [](const json& v, double lo, double hi, bool lo_open, double& out) {
    if (!v.is_number() || !std::isfinite(v.get<double>())) return false;
    const double x = v.get<double>();
    if (lo_open ? !(x > lo) : !(x >= lo)) return false;
    if (!(x <= hi)) return false;
    out = x;
    return true;
  };
  for (const auto& [name, text] : inputs) {
    const json v = parse_value(text);
    std::smatch m;
    if (name == "reservoir.forcing.model") {
      if (!v.is_string() || (v != "none" && v != "exponential" && v != "table"))
        return name + ": must be one of none|exponential|table (got " + v.dump() + ")";
      g.forcing = v.get<std::string>();
    } else if (name == "reservoir.forcing.t99_s") {
      if (!number_in(v, 0.0, 60.0, true, g.t99_s))
        return name + ": must be a number in (0, 60] s (got " + v.dump() + ")";
    } else if (name == "reservoir.gate_height_m") {
      if (!number_in(v, 0.0, 0.5, true, g.gate_height_m))
        return name + ": must be a number in (0, 0.5] m (got " + v.dump() + ")";
    } else if (name == "reservoir.fill_level_m") {
      if (!number_in(v, 0.0, 2.0, true, g.fill_level_m))
        return name + ": must be a number in (0, 2] m (got " + v.dump() + ")";
    } else if (name == "basin.still_water_m") {
      if (!number_in(v, 0.0, 1.0, true, g.still_water_m))
        return name + ": must be a number in (0, 1] m (got " + v.dump() + ")";
    } else if (name == "solver.end_time") {
      if (!number_in(v, 0.0, 60.0, true, g.end_time))
        return name + ": must be a number in (0, 60] s (got " + v.dump() + ")";
    } else if (name == "undulation_m") {
      if (!number_in(v, 0.0, 0.1, false, g.undulation_m))
        return name + ": must be a number in [0, 0.1] m (got " + v.dump() + ")";
    } else if (name == "sleep_s") {
      if (!number_in(v, 0.0, 3600.0, false, g.sleep_s))
        return name + ": must be in [0, 3600] (got " + v.dump() + ")";
    } else if (name == "reservoir.forcing.table") {
      if (!v.is_array() || v.empty()) return name + ": must be a non-empty array of [time_s, hold] pairs";
      g.table.clear();
      for (const auto& p : v) {
        if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
          return name + ": must be an array of [time_s, hold] pairs (got " + p.dump() + ")";
        g.table.push_back({p[0].get<double>(), p[1].get<double>()});
      }
    } else if (std::regex_match(name, m, element)) {
      const size_t i = std::stoul(m[1].str()), j = std::stoul(m[2].str());
      if (i >= g.table.size() || j > 1)
        return name + ": no such element (the table has " + std::to_string(g.table.size()) +
               " control points [time_s, hold]; indices 0.." + std::to_string(g.table.size() - 1) +
               " and 0|1)";
      if (!v.is_number() || !std::isfinite(v.get<double>()))
        return name + ": must be a finite number (got " + v.dump() + ")";
      g.table[i][j] = v.get<double>();
    } else {
      std::string allowed;
      for (const auto& n : gauge_model_inputs()) allowed += (allowed.empty() ? "" : ", ") + n;
      return name + ": not an input of model gauge (its inputs: " + allowed +
             ", reservoir.forcing.table.<i>.<0|1>)";
    }
  }
  for (size_t i = 0; i < g.table.size(); ++i) {
    if (!(g.table[i][1] >= 0.0 && g.table[i][1] <= 1.0))
      return "reservoir.forcing.table." + std::to_string(i) + ".1: a hold fraction must be in [0, 1] (got " +
             gauge_fmt(g.table[i][1]) + ")";
    if (i > 0 && !(g.table[i][0] > g.table[i - 1][0]))
      return "reservoir.forcing.table." + std::to_string(i) + ".0: control point times must increase (got " +
             gauge_fmt(g.table[i - 1][0]) + " then " + gauge_fmt(g.table[i][0]) + ")";
  }
  if (!(g.fill_level_m > g.still_water_m))
    return "reservoir.fill_level_m: must be above basin.still_water_m (" + gauge_fmt(g.still_water_m) + " m)";
  return "";
}

// The hold fraction f(t): 1 holds the reservoir's extra head, 0 releases it.
double gauge_hold(const GaugeInputs& g, double t) {
  if (g.forcing == "none") return 0.0;
  if (g.forcing == "exponential") return std::exp(-t * std::log(100.0) / g.t99_s);
  const auto& tab = g.table;
  if (t <= tab.front()[0]) return tab.front()[1];
  if (t >= tab.back()[0]) return tab.back()[1];
  size_t k = 1;
  while (tab[k][0] < t) ++k;
  const double w = (t - tab[k - 1][0]) / (tab[k][0] - tab[k - 1][0]);
  return tab[k - 1][1] + w * (tab[k][1] - tab[k - 1][1]);
}

// Trailing undulations behind the front (a test hook, off at 0): amplitude `amplitude_m`, period
// 0.25 s sqrt(0.1 m / H) with H the front's height, as an undular bore's waves lengthen when it weakens
// (Peregrine 1966). Their phase t / T drifts with H, so over a long window the misfit has a local minimum
// every period (cycle skipping) while the first period stays convex: the calibration tests' case for
// window continuation.
void add_undulations(double amplitude_m, double front_s, const std::vector<double>& time,
                     std::vector<double>& elevation) {
  if (amplitude_m <= 0) return;
  const double height = *std::max_element(elevation.begin(), elevation.end());
  if (!(height > 0)) return;
  const double period = 0.25 * std::sqrt(0.1 / height), pi = 3.14159265358979323846;
  for (size_t k = 0; k < time.size(); ++k) {
    const double s = time[k] - front_s;
    if (s > 0) elevation[k] += amplitude_m * (1.0 - std::exp(-s / 0.1)) * std::sin(2 * pi * s / period);
  }
}

struct GaugeRecord {
  std::string name;
  std::vector<double> time, elevation;
};

// Reservoir (x 0-0.5 m) draining through the gate opening a: q = Cd a sqrt(2 g (1 - f) H) per unit width
// (sluice-gate orifice law, Cd = 0.61, Henderson 1966 sec. 6.4), dH/dt = -q / L. At a gauge at distance d
// from the gate, a linear long wave eta = q(t - d/c)/c, c = sqrt(g h0) (Lamb 1932 sec. 170), smoothed by a
// Gaussian of 0.02 s + 0.03 s/m d standing in for dispersion. Returns WG1..WG4 at 100 Hz and the ODE steps.
std::vector<GaugeRecord> gauge_records(const GaugeInputs& g, std::int64_t& steps) {
  const double grav = 9.80665, cd = 0.61, reservoir_length = 0.5, x_gate = 0.52;
  const double dt = 1e-4;
  const auto n_q = static_cast<size_t>(std::ceil(g.end_time / dt)) + 1;
  std::vector<double> q(n_q, 0.0);
  double head = g.fill_level_m - g.still_water_m;
  auto rate = [&](double t, double h) {
    const double open = std::max(0.0, 1.0 - gauge_hold(g, t));
    return cd * g.gate_height_m * std::sqrt(2.0 * grav * open * std::max(h, 0.0));
  };
  for (size_t k = 0; k < n_q; ++k) {
    const double t = k * dt;
    q[k] = rate(t, head);
    // RK4 on dH/dt = -q(t, H) / L.
    const double k1 = -rate(t, head) / reservoir_length;
    const double k2 = -rate(t + dt / 2, head + dt / 2 * k1) / reservoir_length;
    const double k3 = -rate(t + dt / 2, head + dt / 2 * k2) / reservoir_length;
    const double k4 = -rate(t + dt, head + dt * k3) / reservoir_length;
    head = std::max(0.0, head + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4));
    ++steps;
  }
  auto q_at = [&](double t) {
    if (t <= 0) return 0.0;
    const double u = t / dt;
    const auto i = static_cast<size_t>(u);
    if (i + 1 >= n_q) return q.back();
    return q[i] + (u - i) * (q[i + 1] - q[i]);
  };
  const double c = std::sqrt(grav * g.still_water_m);
  // Positions of Goseberg et al. 2016b Table 1 in the scene's frame (issue 3).
  const std::vector<std::pair<std::string, double>> gauges = {
      {"WG1", 1.85}, {"WG2", 3.64}, {"WG3", 4.69}, {"WG4", 6.15}};
  const auto n_t = static_cast<size_t>(std::llround(g.end_time * 100.0)) + 1;
  std::vector<GaugeRecord> out;
  for (const auto& [name, x] : gauges) {
    GaugeRecord r{name, {}, {}};
    const double d = x - x_gate, delay = d / c, sigma = 0.02 + 0.03 * d;
    const double attenuation = std::exp(-std::max(0.0, x - 1.85) / 8.0);
    const double ds = 1e-3;
    const int half = static_cast<int>(std::ceil(4 * sigma / ds));
    double norm = 0;
    for (int j = -half; j <= half; ++j) norm += std::exp(-0.5 * std::pow(j * ds / sigma, 2));
    for (size_t k = 0; k < n_t; ++k) {
      const double t = k / 100.0;
      double sum = 0;
      for (int j = -half; j <= half; ++j)
        sum += std::exp(-0.5 * std::pow(j * ds / sigma, 2)) * q_at(t - delay - j * ds);
      r.time.push_back(t);
      r.elevation.push_back(attenuation * sum / norm / c);
    }
    add_undulations(g.undulation_m, delay, r.time, r.elevation);
    out.push_back(std::move(r));
  }
  return out;
}

// Writes result.h5 and returns the metrics `flume run` reports for a gauge.
void write_gauges(const GaugeInputs& g, const std::string& out_dir, std::map<std::string, double>& metrics,
                  std::int64_t& steps) {
  const auto records = gauge_records(g, steps);
  h5::RunFile file((std::filesystem::path(out_dir) / "result.h5").string());
  for (const auto& r : records) {
    file.write_series("/gauges/" + r.name, "time", r.time);
    file.write_series("/gauges/" + r.name, "elevation", r.elevation);
    size_t peak = 0;
    for (size_t k = 0; k < r.elevation.size(); ++k)
      if (r.elevation[k] > r.elevation[peak]) peak = k;
    metrics[r.name + ".peak_m"] = r.elevation[peak];
    metrics[r.name + ".peak_time_s"] = r.time[peak];
    bool arrived = false;
    for (size_t k = 0; k < r.elevation.size() && !arrived; ++k)
      if (r.elevation[k] > 0.005) {
        metrics[r.name + ".arrival_s"] = r.time[k];
        arrived = true;
      }
    metrics[r.name + ".arrived"] = arrived ? 1.0 : 0.0;
  }
  file.set_attribute("/", "scene", "gauge (test stand-in model)");
  file.set_attribute("/", "status", "complete");
  file.finalize();
}

}  // namespace

std::vector<std::string> gauge_model_inputs() {
  return {"reservoir.forcing.model",
          "reservoir.forcing.t99_s",
          "reservoir.forcing.table",
          "reservoir.gate_height_m",
          "reservoir.fill_level_m",
          "basin.still_water_m",
          "solver.end_time",
          "undulation_m",
          "sleep_s"};
}

std::vector<std::string> gauge_model_gauges() { return {"WG1", "WG2", "WG3", "WG4"}; }

double gauge_model_end_time(const std::vector<std::pair<std::string, std::string>>& inputs) {
  GaugeInputs g;
  read_gauge_inputs(inputs, g);
  return g.end_time;
}

std::string check_gauge_inputs(const std::vector<std::pair<std::string, std::string>>& inputs) {
  GaugeInputs g;
  return read_gauge_inputs(inputs, g);
}

void run_gauge_model(const std::vector<std::pair<std::string, std::string>>& inputs,
                     const std::string& out_dir, std::map<std::string, double>& metrics,
                     std::int64_t& steps) {
  GaugeInputs g;
  const std::string problem = read_gauge_inputs(inputs, g);
  if (!problem.empty()) throw std::invalid_argument(problem);
  if (g.sleep_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(g.sleep_s));
  write_gauges(g, out_dir, metrics, steps);
}

}  // namespace flume::campaigns
