#include "common/input/overrides.h"

#include <cstdlib>

#include "common/errors.h"
#include "common/input/json_input.h"

namespace flume {
namespace {

constexpr std::size_t kMaxPathLength = 256;

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> segs;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    segs.push_back(path.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (dot == std::string::npos) return segs;
    start = dot + 1;
  }
}

bool valid_utf8(const std::string& text) {
  try {
    (void)nlohmann::json(text).dump();
    return true;
  } catch (const nlohmann::json::type_error&) {
    return false;
  }
}

}  // namespace

Override parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set", text, "expected path=value, e.g. --set solver.dx=0.01");
  Override o{text.substr(0, eq), text.substr(eq + 1)};
  if (o.path.size() > kMaxPathLength)
    throw InputError("--set", o.path.substr(0, 40) + "...",
                     "a path of " + std::to_string(o.path.size()) + " characters (allowed: at most " +
                         std::to_string(kMaxPathLength) + ")");
  for (const std::string& seg : split_path(o.path))
    if (seg.empty())
      throw InputError("--set", o.path,
                       "an empty segment in the path (allowed: field names joined by single dots, e.g. solver.dx "
                       "or water.0.hi)");
  return o;
}

namespace input {

void apply_override(nlohmann::json& root, const Override& o, const std::string& label) {
  using json = nlohmann::json;
  // Checked again here: an Override may be built without parse_override (a campaign's own parameter paths).
  if (o.path.empty()) throw InputError(label, o.path, "empty override path");
  const std::vector<std::string> segs = split_path(o.path);
  for (const std::string& s : segs)
    if (s.empty()) throw InputError(label, o.path, "an empty segment in the path (e.g. solver.dx, water.0.hi)");
  // Keys and plain-string values become JSON strings, which must be UTF-8 (the scene is dumped as JSON;
  // invalid bytes ended as "internal error: invalid UTF-8 byte", found by tests/fuzz/fuzz_set).
  if (!valid_utf8(o.path)) throw InputError(label, "", "the --set path is not valid UTF-8");
  const std::optional<json> parsed = parse_json_value(o.value, label, o.path);
  if (!parsed && !valid_utf8(o.value)) throw InputError(label, o.path, "the --set value is not valid UTF-8");
  const json value = parsed ? *parsed : json(o.value);  // not JSON: a plain string such as `float`
  json* node = &root;
  std::string walked;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const std::string& s = segs[i];
    walked += (walked.empty() ? "" : ".") + s;
    if (node->is_array()) {
      char* end = nullptr;
      const long idx = std::strtol(s.c_str(), &end, 10);
      if (*end || idx < 0 || idx >= static_cast<long>(node->size()))
        throw InputError(label, walked,
                         "no such array element (the array has " + std::to_string(node->size()) + " elements)");
      node = &(*node)[static_cast<std::size_t>(idx)];
    } else if (node->is_object() || node->is_null()) {
      node = &(*node)[s];
    } else {
      throw InputError(label, walked, "cannot set a field inside a value that is not an object or array");
    }
  }
  *node = value;
}

nlohmann::json load_with_overrides(const std::string& file, const std::string& what,
                                   const std::vector<Override>& overrides) {
  nlohmann::json root = load_json_document(file, what);
  for (const auto& o : overrides) apply_override(root, o, file + " (--set " + o.path + ")");
  return root;
}

}  // namespace input
}  // namespace flume
