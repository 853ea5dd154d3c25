// Reading one JSON object of a user's document against its description (fields.h): each accessor takes the
// field's key, reads its type, default and range from the description and throws flume::InputError
// "<file>: <field.path>: <problem and what is allowed>"; finish() refuses every field nobody read, so a
// misspelt field is an error rather than a silently ignored default. Reading a key the description lacks is a
// programming error (std::logic_error): the parser cannot accept a field its reference does not list.
#pragma once
#include <array>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/input/fields.h"

namespace flume::input {

// Bounds tighter than the description's, where they follow from other fields (e.g. dx below a quarter of
// the domain).
struct Bounds {
  double lo, hi;
  bool lo_open = false, hi_open = false;
};

class FieldReader {
 public:
  FieldReader(const nlohmann::json& j, const ObjectDoc& doc, std::string path, std::string file);

  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  std::string join(const std::string& key) const;
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  const ObjectDoc& doc() const { return doc_; }

  bool has(const std::string& key) const;
  const nlohmann::json& raw(const std::string& key);  // marks it read
  void accept(const std::string& key);                // marks it read without reading it (a later pass does)

  // The description's default and range, or `b` / `def` where they follow from other fields.
  double number(const std::string& key, std::optional<Bounds> b = std::nullopt);
  double number_or(const std::string& key, double def, std::optional<Bounds> b = std::nullopt);
  long long integer(const std::string& key, std::optional<std::pair<long long, long long>> b = std::nullopt);
  long long integer_or(const std::string& key, long long def,
                       std::optional<std::pair<long long, long long>> b = std::nullopt);
  bool boolean(const std::string& key);
  std::string string(const std::string& key);
  std::string string_or(const std::string& key, const std::string& def);
  std::string choice(const std::string& key);
  std::string choice_or(const std::string& key, const std::string& def);
  // A choice mapped to its value (an enum).
  template <typename E>
  E choice(const std::string& key, const std::vector<std::pair<const char*, E>>& values) {
    const std::string s = choice(key);
    for (const auto& v : values)
      if (s == v.first) return v.second;
    fail(key, "has no value for '" + s + "' (internal)");
  }
  // An array of `n` finite numbers (n within the description's item counts); `def` where absent.
  std::array<double, 3> vec(const std::string& key, int n,
                            std::optional<std::array<double, 3>> def = std::nullopt);
  FieldReader object(const std::string& key);                // absent: an empty object
  std::vector<FieldReader> objects(const std::string& key);  // an array of objects; absent: none
  const nlohmann::json& array(const std::string& key);       // any array, checked by the caller; absent: []
  const nlohmann::json& map(const std::string& key);         // an object with free keys; absent: {}

  void finish() const;

 private:
  const Field& field(const std::string& key, FieldType type) const;
  const Field& described(const std::string& key) const;
  [[noreturn]] void missing(const Field& f, const std::string& what) const;

  const nlohmann::json& j_;
  const ObjectDoc& doc_;
  std::string path_;
  std::string file_;
  std::set<std::string> used_;
};

}  // namespace flume::input
