// Reading a user's JSON document (scene, campaign, calibration or study spec, a `--set` value) with bounds
// checked before anything is allocated from it: a regular file, a bounded size, nesting depth, string length
// and array length, numbers that fit a double, and an object at the top. Every violation is a flume::InputError
// "<file>: <field.path>: <problem and allowed range>". The limits and why are listed in docs/reliability.md.
#pragma once
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace flume::input {

struct JsonLimits {
  std::size_t max_bytes = std::size_t{4} << 20;  // a document; the largest shipped one is under 2 kB
  int max_depth = 64;                            // nested objects/arrays; shipped documents reach 5
  std::size_t max_string = 4096;                 // bytes of a key or string value: a path (PATH_MAX) fits
  std::size_t max_elements = 100000;             // members of one object or elements of one array
};

// The whole of `file` as text: it must be a regular file (not a device, fifo or folder) of at most
// `max_bytes`, checked before reading. `what` names the document in messages ("scene file").
std::string read_input_file(const std::string& file, std::size_t max_bytes, const std::string& what);

// Parses a document that must be a JSON object.
nlohmann::json parse_json_document(const std::string& text, const std::string& file, const JsonLimits& limits = {});
// Reads and parses `file` (read_input_file, then parse_json_document).
nlohmann::json load_json_document(const std::string& file, const std::string& what, const JsonLimits& limits = {});

// Parses one JSON value of any type given for `field` (a `--set` value). Returns nullopt when the text is not
// JSON at all (the caller may take it as a plain string); a value that is JSON but breaks a limit (a number
// that overflows a double, too deep, too long) throws InputError naming `file` and `field`.
std::optional<nlohmann::json> parse_json_value(const std::string& text, const std::string& file,
                                               const std::string& field, const JsonLimits& limits = {});

// "an object", "a number", ...: a JSON value's type as messages name it.
const char* type_name(const nlohmann::json& j);

}  // namespace flume::input
