#include "common/input/field_reader.h"

#include <cmath>
#include <stdexcept>

#include "common/errors.h"
#include "common/input/json_input.h"

namespace flume::input {

using json = nlohmann::json;

FieldReader::FieldReader(const json& j, const ObjectDoc& doc, std::string path, std::string file)
    : j_(j), doc_(doc), path_(std::move(path)), file_(std::move(file)) {
  if (!j_.is_object()) fail("", std::string("must be an object, got ") + type_name(j_));
}

void FieldReader::fail(const std::string& key, const std::string& what) const {
  throw InputError(file_, join(key), what);
}

std::string FieldReader::join(const std::string& key) const {
  if (key.empty()) return path_;
  return path_.empty() ? key : path_ + "." + key;
}

const Field& FieldReader::described(const std::string& key) const {
  const Field* f = doc_.find(key);
  if (!f)
    throw std::logic_error("the parser reads " + join(key) + ", which the description of '" + doc_.title +
                           "' does not list (common/input/fields.h)");
  return *f;
}

const Field& FieldReader::field(const std::string& key, FieldType type) const {
  const Field& f = described(key);
  if (f.type != type)
    throw std::logic_error("the parser reads " + join(key) + " as another type than its description says");
  return f;
}

bool FieldReader::has(const std::string& key) const {
  described(key);
  return j_.contains(key);
}

const json& FieldReader::raw(const std::string& key) {
  described(key);
  used_.insert(key);
  return j_.at(key);
}

void FieldReader::accept(const std::string& key) {
  if (!doc_.free_keys) described(key);
  used_.insert(key);
}

void FieldReader::missing(const Field& f, const std::string& what) const {
  fail(f.key, "is required (" + what + ")");
}

double FieldReader::number_or(const std::string& key, double def, std::optional<Bounds> b) {
  const Field& f = field(key, FieldType::kNumber);
  const Bounds r = b ? *b : Bounds{f.lo, f.hi, f.lo_open, f.hi_open};
  const std::string range = range_text(r.lo, r.hi, r.lo_open, r.hi_open);
  if (!has(key)) return def;
  const json& v = raw(key);
  if (!v.is_number()) fail(key, "must be a number in " + range + ", got " + type_name(v));
  const double x = v.get<double>();
  const bool ok =
      std::isfinite(x) && (r.lo_open ? x > r.lo : x >= r.lo) && (r.hi_open ? x < r.hi : x <= r.hi);
  if (!ok) fail(key, "must be in " + range + " (got " + number_text(x) + ")");
  return x;
}

double FieldReader::number(const std::string& key, std::optional<Bounds> b) {
  const Field& f = field(key, FieldType::kNumber);
  if (!has(key)) {
    if (!f.default_value.is_number()) {
      const Bounds r = b ? *b : Bounds{f.lo, f.hi, f.lo_open, f.hi_open};
      missing(f, "a number in " + range_text(r.lo, r.hi, r.lo_open, r.hi_open));
    }
    return f.default_value.get<double>();
  }
  return number_or(key, 0.0, b);
}

long long FieldReader::integer_or(const std::string& key, long long def,
                                  std::optional<std::pair<long long, long long>> b) {
  const Field& f = field(key, FieldType::kInteger);
  const double lo = b ? static_cast<double>(b->first) : f.lo, hi = b ? static_cast<double>(b->second) : f.hi;
  const std::string range = integer_range_text(lo, hi);
  if (!has(key)) return def;
  const json& v = raw(key);
  if (!v.is_number() || std::floor(v.get<double>()) != v.get<double>())
    fail(key, "must be an integer in " + range + ", got " +
                  (v.is_number() ? number_text(v.get<double>()) : std::string(type_name(v))));
  const double x = v.get<double>();
  if (x < lo || x > hi) fail(key, "must be in " + range + " (got " + number_text(x) + ")");
  return static_cast<long long>(x);
}

long long FieldReader::integer(const std::string& key, std::optional<std::pair<long long, long long>> b) {
  const Field& f = field(key, FieldType::kInteger);
  if (!has(key)) {
    const double lo = b ? static_cast<double>(b->first) : f.lo,
                 hi = b ? static_cast<double>(b->second) : f.hi;
    if (!f.default_value.is_number()) missing(f, "an integer in " + integer_range_text(lo, hi));
    return f.default_value.get<long long>();
  }
  return integer_or(key, 0, b);
}

bool FieldReader::boolean(const std::string& key) {
  const Field& f = field(key, FieldType::kBoolean);
  if (!has(key)) {
    if (!f.default_value.is_boolean()) missing(f, "true or false");
    return f.default_value.get<bool>();
  }
  const json& v = raw(key);
  if (!v.is_boolean()) fail(key, std::string("must be true or false, got ") + type_name(v));
  return v.get<bool>();
}

std::string FieldReader::string_or(const std::string& key, const std::string& def) {
  field(key, FieldType::kString);
  if (!has(key)) return def;
  const json& v = raw(key);
  if (!v.is_string()) fail(key, std::string("must be a string, got ") + type_name(v));
  return v.get<std::string>();
}

std::string FieldReader::string(const std::string& key) {
  const Field& f = field(key, FieldType::kString);
  if (!has(key)) {
    if (!f.default_value.is_string()) missing(f, "a string");
    return f.default_value.get<std::string>();
  }
  return string_or(key, "");
}

std::string FieldReader::choice_or(const std::string& key, const std::string& def) {
  const Field& f = field(key, FieldType::kChoice);
  std::string allowed;
  for (const auto& o : f.choices) allowed += (allowed.empty() ? "" : "|") + o;
  if (!has(key)) return def;
  const json& v = raw(key);
  if (!v.is_string()) fail(key, "must be one of " + allowed + ", got " + type_name(v));
  for (const auto& o : f.choices)
    if (v.get<std::string>() == o) return o;
  fail(key, "must be one of " + allowed + " (got '" + v.get<std::string>() + "')");
}

std::string FieldReader::choice(const std::string& key) {
  const Field& f = field(key, FieldType::kChoice);
  if (!has(key)) {
    std::string allowed;
    for (const auto& o : f.choices) allowed += (allowed.empty() ? "" : "|") + o;
    if (!f.default_value.is_string()) missing(f, "one of " + allowed);
    return f.default_value.get<std::string>();
  }
  return choice_or(key, "");
}

std::array<double, 3> FieldReader::vec(const std::string& key, int n,
                                       std::optional<std::array<double, 3>> def) {
  const Field& f = field(key, FieldType::kVector);
  if (n < f.min_items || n > f.max_items || n > 3)
    throw std::logic_error("the parser reads " + join(key) + " with a length its description does not allow");
  const std::string what = "an array of " + std::to_string(n) + " numbers";
  if (!has(key)) {
    if (!def) missing(f, what);
    return *def;
  }
  const json& v = raw(key);
  if (!v.is_array() || static_cast<int>(v.size()) != n)
    fail(key, "must be " + what + (f.min_items != f.max_items ? " (the scene's dimension)" : ""));
  std::array<double, 3> out{};
  for (int i = 0; i < n; ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
      fail(key + "." + std::to_string(i), "must be a finite number");
    out[i] = v[i].get<double>();
  }
  return out;
}

FieldReader FieldReader::object(const std::string& key) {
  static const json empty = json::object();
  const Field& f = field(key, FieldType::kObject);
  return FieldReader(has(key) ? raw(key) : empty, *f.object, join(key), file_);
}

std::vector<FieldReader> FieldReader::objects(const std::string& key) {
  const Field& f = field(key, FieldType::kObjectArray);
  std::vector<FieldReader> out;
  if (!has(key)) return out;
  const json& v = raw(key);
  if (!v.is_array()) fail(key, std::string("must be an array, got ") + type_name(v));
  for (size_t i = 0; i < v.size(); ++i)
    out.emplace_back(v[i], *f.object, join(key) + "." + std::to_string(i), file_);
  return out;
}

const json& FieldReader::array(const std::string& key) {
  static const json empty = json::array();
  if (!has(key)) return empty;
  const json& v = raw(key);
  if (!v.is_array()) fail(key, std::string("must be an array, got ") + type_name(v));
  return v;
}

const json& FieldReader::map(const std::string& key) {
  static const json empty = json::object();
  field(key, FieldType::kMap);
  if (!has(key)) return empty;
  const json& v = raw(key);
  if (!v.is_object()) fail(key, std::string("must be an object, got ") + type_name(v));
  return v;
}

void FieldReader::finish() const {
  for (auto it = j_.begin(); it != j_.end(); ++it) {
    if (used_.count(it.key())) continue;
    std::set<std::string> known;
    for (const auto& f : doc_.fields) known.insert(f.key);
    std::string allowed;
    for (const auto& k : known) allowed += (allowed.empty() ? "" : ", ") + k;
    fail(it.key(), "unknown field" + (allowed.empty() ? std::string() : " (known here: " + allowed + ")"));
  }
}

}  // namespace flume::input
