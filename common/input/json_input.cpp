#include "common/input/json_input.h"

#include <filesystem>
#include <fstream>
#include <vector>

#include "common/errors.h"

namespace flume::input {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Thrown by the parser callback to stop at the first violation; carries the field path to the caller.
struct LimitExceeded {
  std::string field, problem;
};

// Tracks where the parser is (a field path such as "water.3.hi") and checks the limits as values arrive, so
// a 60,000-deep array stops at depth 65 instead of being built (and later dumped recursively).
class Guard {
 public:
  explicit Guard(const JsonLimits& limits) : limits_(limits) {}

  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        start_element();
        if (static_cast<int>(frames_.size()) >= limits_.max_depth)
          throw LimitExceeded{path(false), "nested deeper than " + std::to_string(limits_.max_depth) +
                                              " levels (allowed: at most " + std::to_string(limits_.max_depth) + ")"};
        frames_.push_back({event == json::parse_event_t::array_start, std::string(), 0});
        break;
      case json::parse_event_t::key:
        frames_.back().key = parsed.get<std::string>();
        check_string(parsed, "a key");
        break;
      case json::parse_event_t::value:
        start_element();
        check_string(parsed, "a string");
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        break;
    }
    return true;
  }

  // The field path; `pending`: an element of the innermost array is being read but not yet counted (the
  // parser failed inside it, e.g. on a number that overflows).
  std::string path(bool pending) const {
    std::string p;
    for (std::size_t i = 0; i < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      std::string seg;
      if (f.array) {
        const bool innermost = i + 1 == frames_.size();
        const std::size_t index = innermost && pending ? f.count : f.count - 1;
        if (innermost && !pending && f.count == 0) break;
        seg = std::to_string(index);
      } else {
        seg = f.key;
      }
      if (seg.empty()) break;
      p += (p.empty() ? "" : ".") + seg;
    }
    return p;
  }

 private:
  struct Frame {
    bool array;
    std::string key;
    std::size_t count;
  };

  void start_element() {
    if (frames_.empty()) return;
    Frame& f = frames_.back();
    if (f.array || !f.key.empty()) ++f.count;
    if (f.count > limits_.max_elements)
      throw LimitExceeded{path(false), std::string("has more than ") + std::to_string(limits_.max_elements) +
                                           (f.array ? " elements" : " fields") + " (allowed: at most " +
                                           std::to_string(limits_.max_elements) + ")"};
  }
  void check_string(const json& v, const char* what) const {
    if (v.is_string() && v.get_ref<const std::string&>().size() > limits_.max_string)
      throw LimitExceeded{path(false), std::string(what) + " of " +
                                           std::to_string(v.get_ref<const std::string&>().size()) +
                                           " bytes (allowed: at most " + std::to_string(limits_.max_string) + ")"};
  }

  const JsonLimits& limits_;
  std::vector<Frame> frames_;
};

// Parses with the guard; `syntax_ok` receives false (and nothing is thrown) on a syntax error when the
// caller wants to fall back to a plain string.
std::optional<json> guarded_parse(const std::string& text, const std::string& file, const std::string& field_prefix,
                                  const JsonLimits& limits, bool syntax_error_is_nullopt) {
  auto full = [&](const std::string& sub) {
    if (field_prefix.empty()) return sub;
    return sub.empty() ? field_prefix : field_prefix + "." + sub;
  };
  if (text.size() > limits.max_bytes)
    throw InputError(file, field_prefix,
                     "is " + std::to_string(text.size()) + " bytes (allowed: at most " +
                         std::to_string(limits.max_bytes) + ")");
  Guard guard(limits);
  try {
    return json::parse(text, std::ref(guard));
  } catch (const LimitExceeded& e) {
    throw InputError(file, full(e.field), e.problem);
  } catch (const json::out_of_range& e) {
    // nlohmann's only out_of_range while parsing: a number beyond a double (1e999).
    throw InputError(file, full(guard.path(true)),
                     "a number out of range: JSON numbers must fit a double (|x| < 1.8e308) (" +
                         std::string(e.what()) + ")");
  } catch (const json::parse_error& e) {
    if (syntax_error_is_nullopt) return std::nullopt;
    throw InputError(file, full(""), std::string("not valid JSON: ") + e.what());
  }
}


}  // namespace

const char* type_name(const json& j) {
  switch (j.type()) {
    case json::value_t::null: return "null";
    case json::value_t::boolean: return "a boolean";
    case json::value_t::string: return "a string";
    case json::value_t::array: return "an array";
    case json::value_t::object: return "an object";
    default: return "a number";
  }
}

std::string read_input_file(const std::string& file, std::size_t max_bytes, const std::string& what) {
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (ec || !fs::exists(st)) throw InputError(file, "", "cannot open the " + what + ": no such file");
  if (!fs::is_regular_file(st))
    throw InputError(file, "", "the " + what + " must be a regular file (not a folder, device or pipe)");
  const std::uintmax_t size = fs::file_size(file, ec);
  if (ec) throw InputError(file, "", "cannot read the size of the " + what + ": " + ec.message());
  if (size > max_bytes)
    throw InputError(file, "", "the " + what + " is " + std::to_string(size) + " bytes (allowed: at most " +
                                   std::to_string(max_bytes) + ")");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "", "cannot open the " + what);
  // Read at most max_bytes + 1: a file that grew since it was measured is still refused, never read whole.
  std::string text(static_cast<std::size_t>(size) + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > max_bytes)
    throw InputError(file, "", "the " + what + " grew past " + std::to_string(max_bytes) + " bytes while read");
  return text;
}

json parse_json_document(const std::string& text, const std::string& file, const JsonLimits& limits) {
  json root = *guarded_parse(text, file, "", limits, false);
  if (!root.is_object())
    throw InputError(file, "", std::string("not an object: the document must be a JSON object {...}, got ") +
                                   type_name(root));
  return root;
}

json load_json_document(const std::string& file, const std::string& what, const JsonLimits& limits) {
  return parse_json_document(read_input_file(file, limits.max_bytes, what), file, limits);
}

std::optional<json> parse_json_value(const std::string& text, const std::string& file, const std::string& field,
                                     const JsonLimits& limits) {
  return guarded_parse(text, file, field, limits, true);
}

}  // namespace flume::input
