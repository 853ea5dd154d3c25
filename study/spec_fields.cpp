#include "study/spec_fields.h"

#include "campaigns/spec_fields.h"

namespace flume::study {

using namespace input;
using json = nlohmann::json;

const ObjectDoc& study_outputs_doc() {
  static const ObjectDoc d{
      "outputs",
      "What is compared between a setting and the reference.",
      {value("gauges", json::parse(R"({"type": "array", "items": {"type": "string"}})"), "array of names",
             "gauges of the base scene to compare")
           .def_note("all of the scene's")
           .eg(json::array({"WG1"})),
       value("loads", json::parse(R"({"type": "array", "items": {"type": "string"}})"), "array of names",
             "load cells of the base scene to compare")
           .def_note("all of the scene's (none against a measured record)")
           .eg(json::array()),
       value("window_s", json::parse(R"({"type": "array", "items": {"type": "number", "minimum": 0},
                                        "minItems": 2, "maxItems": 2})"),
             "array [t0, t1]", "the time window compared")
           .in_unit("s")
           .def_note("[0, solver.end_time]")
           .note("0 <= t0 < t1")
           .eg(json::array({0.0, 1.0})),
       number("arrival_threshold_m", "a gauge's arrival: the first rise this far above its first reading")
           .above(0)
           .at_most(1)
           .in_unit("m")
           .def(0.005),
       number("front_s", "RMS over this long after the reference's arrival; 0: over the whole window")
           .at_least(0)
           .in_unit("s")
           .def(0.0)
           .note("at most the window's length"),
       value("metrics", json::parse(R"({"type": "array", "items": {"oneOf": [{"type": "string"},
                 {"type": "object", "properties": {"name": {"type": "string"}, "scale": {"type": "number", "minimum": 0}},
                  "required": ["name"], "additionalProperties": false}]}})"),
             "array of names or {name, scale}",
             "run.json metrics to compare (`*` matches any characters but '.'); scale: the relative "
             "difference's "
             "least denominator, in the metric's unit")
           .eg(json::array({"D1.rest_x_m"}))}};
  return d;
}

const ObjectDoc& study_reference_doc() {
  static const ObjectDoc d{
      "reference",
      "What the settings are compared with: exactly one of a setting and a measured record.",
      {string("setting", "the label of one of the settings"),
       string("records",
              "a CSV file of gauge records (time_s and a column per gauge), relative to the working "
              "directory or the spec's folder")}};
  return d;
}

const ObjectDoc& study_doc() {
  static const ObjectDoc d = [] {
    const ObjectDoc& campaign = campaigns::campaign_doc();
    ObjectDoc s{
        "study",
        "A study spec (`flume study tradeoff SPEC --db FILE`, docs/tradeoff.md): settings of one scene run "
        "as a campaign with a list design, each compared with the reference over the outputs.",
        {}};
    // Read by the campaign parser, as a campaign spec's.
    for (const char* key : {"name", "description", "scene", "overrides"})
      s.fields.push_back(*campaign.find(key));
    s.fields[2].required = true;  // scene: a study has no model
    s.fields[2].required_when.clear();
    s.fields.push_back(
        value(
            "settings", json::parse(R"({"type": "array", "minItems": 2, "items": {"type": "object",
                 "properties": {"label": {"type": "string", "minLength": 1}}, "required": ["label"],
                 "additionalProperties": {"type": ["number", "string"]}}})"),
            "array of objects {label, path: value, ...}",
            "the fidelity settings, at least two: each a label and the scene paths it sets (`scene`: another "
            "scene file)")
            .needed());
    s.fields.push_back(object("reference", study_reference_doc(), "the reference").needed());
    s.fields.push_back(object("outputs", study_outputs_doc(), "what is compared"));
    s.fields.push_back(*campaign.find("run"));
    return s;
  }();
  return d;
}

}  // namespace flume::study
