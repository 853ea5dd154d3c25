// `--set path=value` overrides of a JSON document: parsed (the path checked), applied to the document's JSON,
// and a document read with its overrides. Shared by the solver (scenes), campaigns and the report, which
// reads a run's settings from its scene file and the --set it ran with.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace flume {

// A `--set path=value` override. The value is read as JSON where it parses as JSON, else as a string.
struct Override {
  std::string path;   // dotted; numeric segments index arrays ("water.0.hi")
  std::string value;  // raw text from the command line
};

// Parses "path=value". Throws InputError when there is no '=', or the path is empty, longer than 256
// characters or has an empty segment ("..", a leading or trailing '.').
Override parse_override(const std::string& text);

namespace input {

// Applies `o` to `root`; `label` names the document in messages. Missing object keys are created (the strict
// parse that follows rejects any that are not fields); an array index must exist.
void apply_override(nlohmann::json& root, const Override& o, const std::string& label);

// The JSON object in `file` (load_json_document) with `overrides` applied, not validated further.
nlohmann::json load_with_overrides(const std::string& file, const std::string& what,
                                   const std::vector<Override>& overrides);

}  // namespace input
}  // namespace flume
