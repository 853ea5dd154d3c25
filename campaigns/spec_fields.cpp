#include "campaigns/spec_fields.h"

#include "campaigns/models.h"

namespace flume::campaigns {

using namespace input;
using json = nlohmann::json;

const ObjectDoc& distribution_doc() {
  static const ObjectDoc d{
      "parameters[].distribution",
      "A parameter's distribution (OpenTURNS). Which fields it takes depends on `type`: uniform (lower, "
      "upper); "
      "normal (mean, std); lognormal (mean and std of the variable, or mu_log and sigma_log); "
      "truncated_normal "
      "(mean, std, lower, upper); beta (alpha, beta, lower, upper); choice (values, weights).",
      {choice("type", {"uniform", "normal", "lognormal", "truncated_normal", "beta", "choice"},
              "the distribution")
           .needed(),
       number("lower", "lower bound")
           .needed_when("by uniform and truncated_normal")
           .def_note("beta: 0")
           .eg(0.0),
       number("upper", "upper bound")
           .needed_when("by uniform and truncated_normal")
           .def_note("beta: 1")
           .eg(1.0),
       number("mean", "mean (of the variable, also for lognormal)")
           .needed_when("by normal, truncated_normal, lognormal without mu_log")
           .note("lognormal: > 0")
           .eg(0.5),
       number("std", "standard deviation").above(0).needed_when("with mean").eg(0.1),
       number("mu_log", "lognormal: mean of log(x)").needed_when("by lognormal without mean").eg(0.0),
       number("sigma_log", "lognormal: standard deviation of log(x)")
           .above(0)
           .needed_when("with mu_log")
           .eg(0.5),
       number("alpha", "beta: first shape parameter").above(0).needed_when("by beta").eg(2.0),
       number("beta", "beta: second shape parameter").above(0).needed_when("by beta").eg(2.0),
       value("values", {{"type", "array"}, {"items", {{"type", json::array({"number", "string"})}}}},
             "array of numbers or of strings", "choice: the values, each once")
           .needed_when("by choice")
           .eg(json::array({1, 2})),
       value("weights", {{"type", "array"}, {"items", {{"type", "number"}, {"minimum", 0}}}},
             "array of numbers", "choice: relative weights of the values")
           .def_note("equal")
           .eg(json::array({1, 1}))}};
  return d;
}

namespace {

const ObjectDoc& parameter_doc() {
  static const ObjectDoc d{
      "parameters[]",
      "An uncertain input: a scene path (as `--set` takes it) or a model input, and its distribution.",
      {string("path", "the scene field it sets (e.g. debris.friction.flume) or the model's input").needed(),
       object("distribution", distribution_doc(), "its distribution").needed()}};
  return d;
}

const ObjectDoc& correlation_doc() {
  static const ObjectDoc d{
      "correlation[]",
      "A rank (Spearman) correlation between two parameters (not with a list design).",
      {value("parameters",
             {{"type", "array"}, {"items", {{"type", "string"}}}, {"minItems", 2}, {"maxItems", 2}},
             "array of two paths", "the two parameters' paths")
           .needed(),
       number("rank", "Spearman rank correlation").in(-0.99, 0.99).needed()}};
  return d;
}

const ObjectDoc& design_doc() {
  static const ObjectDoc d{
      "design",
      "How the parameters are sampled (OpenTURNS), or a list of points given by hand.",
      {choice("type", {"monte_carlo", "lhs", "sobol", "grid", "one_at_a_time", "saltelli", "list"},
              "the design; list: the points below, each setting scene paths (a study's settings)")
           .needed(),
       integer("samples", "number of samples (saltelli: base samples)")
           .in(1, 10000000)
           .needed_when(
               "by monte_carlo, lhs, sobol, saltelli, and grid over continuous parameters without levels")
           .eg(4),
       integer("levels", "grid: levels per parameter (at least 2); one_at_a_time: levels per side")
           .in(1, 1000)
           .def_note("grid: from samples; one_at_a_time: 1")
           .eg(2),
       choice("base", {"monte_carlo", "lhs", "sobol"}, "saltelli: the base design").def("monte_carlo"),
       value("points", json::parse(R"({"type": "array", "minItems": 1, "items": {"type": "object",
                 "properties": {"label": {"type": "string"}},
                 "additionalProperties": {"type": ["number", "string"]}}})"),
             "array of objects {label, path: value, ...}",
             "list: the points; each sets scene paths (or `scene`, another scene file) to numbers or strings")
           .needed_when("by list")}};
  return d;
}

}  // namespace

const ObjectDoc& run_settings_doc() {
  static const ObjectDoc d{
      "run",
      "How each run is run (may change between a job and its resume).",
      {number("time_limit_s", "wall-clock limit of one run")
           .above(0)
           .at_most(30.0 * 86400)
           .def(3600.0)
           .in_unit("s"),
       integer("threads", "OpenMP threads per run").in(1, 1024).def(1),
       number("memory_limit_mb", "address-space limit of one run; 0: none").in(0, 1e9).def(0.0).in_unit("MB"),
       string("output_dir", "where the runs' folders go")
           .def("")
           .def_note("empty: FILE.runs/ beside the database"),
       number("checkpoint_every_s", "a run's checkpoint interval (wall clock); 0: none")
           .in(0, 1e7)
           .def(0.0)
           .in_unit("s")
           .note("0 or at least 1")}};
  return d;
}

const ObjectDoc& campaign_doc() {
  static const ObjectDoc d{
      "campaign",
      "A campaign spec: sampled runs of a scene (or an analytic model) stored in an SQLite database "
      "(`flume campaign run SPEC --db FILE`, docs/campaigns.md).",
      {string("name", "the campaign's name (letters, digits, '_', '-', '.')").needed(),
       string("description", "free text").def(""),
       string("scene", "the scene file, relative to the working directory or the spec's folder")
           .needed_when("unless model is given (exactly one of scene and model)"),
       choice("model", model_names(), "an analytic stand-in for the solver (tests, surrogates)")
           .needed_when("unless scene is given"),
       map("overrides", json::object(), "object {path: value}", "fixed `--set` values of every run"),
       object_array("parameters", parameter_doc(), "the uncertain inputs")
           .needed_when("unless the design is a list"),
       object_array("correlation", correlation_doc(), "rank correlations between parameters"),
       object("design", design_doc(), "the sampling design").needed(),
       integer("seed", "random seed of the design")
           .in(0, 4294967295.0)
           .needed_when("unless the design is a list")
           .def_note("list: 0")
           .eg(1),
       object("run", run_settings_doc(), "how each run is run")}};
  return d;
}

}  // namespace flume::campaigns
