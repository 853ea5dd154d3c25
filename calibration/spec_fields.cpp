#include "calibration/spec_fields.h"

#include "calibration/spec.h"
#include "campaigns/spec_fields.h"

namespace flume::calibration {

using namespace input;
using json = nlohmann::json;

namespace {

std::vector<std::string> local_algorithms() {
  std::vector<std::string> out;
  for (const auto& a : algorithm_names())
    if (is_local_algorithm(a)) out.push_back(a);
  return out;
}

const ObjectDoc& parameter_doc() {
  static const ObjectDoc d{
      "parameters[]",
      "A free parameter: a scene path (as `--set` takes it) or a model input, its bounds and start.",
      {string("path", "the scene field it sets (e.g. reservoir.gate_height_m) or the model's input").needed(),
       choice("scale", {"linear", "log"}, "the optimizer works on the value, or on its logarithm")
           .def("linear"),
       number("lower", "lower bound").needed().note("log scale: > 0"),
       number("upper", "upper bound").needed().note("above lower"),
       number("start", "the first start point").needed().note("in [lower, upper]")}};
  return d;
}

const ObjectDoc& time_shift_doc() {
  static const ObjectDoc d{
      "objective.time_shift",
      "A free shift of the simulated records in time, fitted without new runs.",
      {number("lower", "lower bound").in(-60, 60).needed().in_unit("s"),
       number("upper", "upper bound").in(-60, 60).needed().in_unit("s").note("above lower"),
       number("start", "start value").in(-60, 60).def(0.0).in_unit("s").note("in [lower, upper]")}};
  return d;
}

const ObjectDoc& objective_doc() {
  static const ObjectDoc d{
      "objective",
      "What is minimised: the RMS misfit of the gauges over the window, plus weighted peak and arrival terms "
      "(docs/calibration.md).",
      {value("window", json::parse(R"({"type": "array", "items": {"type": "number", "minimum": 0},
                                      "minItems": 2, "maxItems": 2})"),
             "array [t0, t1]", "the time window compared")
           .in_unit("s")
           .needed()
           .note("0 <= t0 < t1, within the simulated time"),
       value("stages", json::parse(R"({"type": "array", "items": {"type": "number", "minimum": 0},
                                      "maxItems": 16})"),
             "array of end times",
             "window continuation: fit [t0, each end] in turn, each from the one before's optimum, then the "
             "window; absent: the window alone")
           .in_unit("s")
           .eg(json::array({1.8}))
           .note("increasing, each in (t0, t1); needs a local algorithm (docs/calibration.md)"),
       number("peak_weight", "weight of the peak elevation misfit").in(0, 1e6).def(0.0),
       number("arrival_weight_m_per_s", "weight of the arrival time misfit")
           .in(0, 1e6)
           .def(0.0)
           .in_unit("m/s"),
       number("arrival_threshold_m", "a gauge's arrival: the first rise this far above its first reading")
           .above(0)
           .at_most(1)
           .def(0.005)
           .in_unit("m"),
       object("time_shift", time_shift_doc(), "a fitted time shift (absent: none)")}};
  return d;
}

const ObjectDoc& algorithm_doc() {
  static const ObjectDoc d{
      "algorithm",
      "The NLopt optimizer and its budgets (per start).",
      {choice("name", algorithm_names(), "the optimizer (local: BOBYQA needs 2 or more parameters)").needed(),
       choice("local", local_algorithms(), "MLSL's local optimizer").needed_when("by MLSL"),
       choice("polish", local_algorithms(), "a local optimizer run after a global one"),
       integer("max_evaluations", "evaluations per start, and per stage of objective.stages")
           .in(1, 1000000)
           .needed(),
       integer("polish_evaluations", "evaluations of the polish").in(1, 1000000).def(50),
       number("max_time_s", "wall-clock limit per start; 0: none").in(0, 1e9).def(0.0).in_unit("s"),
       number("xtol_abs", "stop when a step moves every parameter less than this (unit cube)")
           .in(0, 0.5)
           .def(1e-4),
       number("ftol_abs", "stop when the objective changes less than this").in(0, 1e3).def(0.0),
       number("initial_step", "first step (unit cube)").above(0).at_most(0.5).def(0.1),
       number("stage_step", "first step of each fit after objective.stages' first (unit cube)")
           .above(0)
           .at_most(0.5)
           .def(0.01),
       integer("population", "population of the global algorithms; 0: NLopt's default").in(0, 100000).def(0),
       integer("seed", "NLopt's random seed").in(0, 4294967295.0).def(1)}};
  return d;
}

const ObjectDoc& multi_start_doc() {
  static const ObjectDoc d{"multi_start",
                           "Quasi-random extra starts (a shifted Halton sequence over the bounds).",
                           {integer("random", "number of extra starts").in(0, 1000).def(0),
                            integer("seed", "seed of the shift").in(0, 4294967295.0).def(1)}};
  return d;
}

const ObjectDoc& profile_doc() {
  static const ObjectDoc d{"profile",
                           "Objective profiles through the optimum, one per parameter.",
                           {integer("points", "points per side; 0: no profiles").in(0, 100).def(5),
                            number("span", "half-width of a profile, a fraction of the parameter's range")
                                .above(0)
                                .at_most(1)
                                .def(0.15)}};
  return d;
}

const ObjectDoc& run_doc() {
  static const ObjectDoc d = [] {
    const ObjectDoc& all = campaigns::run_settings_doc();
    ObjectDoc r{"run", "How each run is run.", {}};
    for (const char* key : {"time_limit_s", "threads", "output_dir"}) r.fields.push_back(*all.find(key));
    return r;
  }();
  return d;
}

const ObjectDoc& target_doc() {
  static const ObjectDoc d{
      "targets[]",
      "A measured record: a CSV file with a time column and gauge columns (docs/calibration.md).",
      {string("file", "the CSV file, relative to the working directory or the spec's folder").needed(),
       number("weight", "weight of its misfit").above(0).at_most(1e6).def(1.0),
       string("gauge", "the one gauge its single data column measures").eg("WG1"),
       map("gauges", {{"type", "string"}}, "object {gauge: column}",
           "gauges and the columns that measure them")}};
  return d;
}

}  // namespace

const ObjectDoc& calibration_doc() {
  static const ObjectDoc d{
      "calibration",
      "A calibration spec: scene parameters fitted to measured gauge records (`flume calibrate SPEC --db "
      "FILE "
      "--out DIR`, docs/calibration.md).",
      {string("name", "the calibration's name (letters, digits, '_', '-', '.')").needed(),
       string("description", "free text").def(""),
       string("scene", "the scene file, relative to the working directory or the spec's folder")
           .def("scenes/waseda/waseda_2d.json")
           .note("not with model"),
       choice("model", {"gauge"}, "an analytic stand-in for the solver (tests)"),
       map("overrides", json::object(), "object {path: value}", "fixed `--set` values of every run"),
       object_array("parameters", parameter_doc(), "the free parameters, at least one").needed(),
       object("objective", objective_doc(), "the misfit").needed(),
       object("algorithm", algorithm_doc(), "the optimizer").needed(),
       value(
           "starts", json::parse(R"({"type": "array", "items": {"type": "object",
                                      "additionalProperties": {"type": "number"}}})"),
           "array of objects {path: value}",
           "extra start points; a path left out starts at its parameter's start (objective.time_shift_s: the "
           "shift)"),
       object("multi_start", multi_start_doc(), "quasi-random starts"),
       object("profile", profile_doc(), "profiles through the optimum"),
       object("run", run_doc(), "how each run is run"),
       object_array("targets", target_doc(), "the measured records, at least one").needed()}};
  return d;
}

}  // namespace flume::calibration
