// The fields of the user's JSON documents (scene, campaign, calibration and study specs), described once:
// each field's type, default, allowed range or choices, unit, meaning and whether it is required. The parsers
// read and check their values through FieldReader (field_reader.h) against these descriptions, and
// `flume schema` prints them as a JSON Schema (draft 2020-12) and as the Markdown references in docs/.
#pragma once
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace flume::input {

enum class FieldType {
  kNumber,   // a finite JSON number
  kInteger,  // a number with no fractional part
  kBoolean,
  kString,
  kChoice,       // one string of `choices`
  kVector,       // an array of min_items..max_items finite numbers (a point, a size)
  kObject,       // an object described by `object`
  kObjectArray,  // an array of objects, each described by `object`
  kMap,    // an object whose keys are free (scene paths, column names); values described by `value_schema`
  kValue,  // any other shape, checked by the parser; described by `value_schema`
};

struct ObjectDoc;

struct Field {
  std::string key;
  FieldType type = FieldType::kNumber;
  std::string meaning;  // one line
  std::string unit;     // "m", "s", "Hz", "kg/m^3", "" for none
  bool required = false;
  std::string
      required_when;  // required only in some documents ("without basin"): the schema leaves it optional
  nlohmann::json default_value;  // null: no static default (see default_note)
  std::string default_note;      // a default that follows from other fields ("4 in 2D, 8 in 3D")
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  std::string range_note;  // bounds that follow from other fields ("below basin.quay_x_m")
  std::vector<std::string> choices;
  int min_items = 0, max_items = 0;   // kVector
  const ObjectDoc* object = nullptr;  // kObject, kObjectArray
  nlohmann::json value_schema;        // kMap (each value), kValue (the whole value): a JSON Schema fragment
  std::string type_text;              // kMap, kValue: the type as the reference names it
  nlohmann::json example;             // a valid value where there is no static default (tests use it)

  // Builders, so that a description reads as one line per field.
  Field& in(double l, double h) {
    lo = l, hi = h;
    return *this;
  }
  Field& above(double l) {
    lo = l, lo_open = true;
    return *this;
  }
  Field& below(double h) {
    hi = h, hi_open = true;
    return *this;
  }
  Field& at_most(double h) {
    hi = h;
    return *this;
  }
  Field& at_least(double l) {
    lo = l;
    return *this;
  }
  Field& def(nlohmann::json v) {
    default_value = std::move(v);
    return *this;
  }
  Field& def_note(std::string n) {
    default_note = std::move(n);
    return *this;
  }
  Field& note(std::string n) {
    range_note = std::move(n);
    return *this;
  }
  Field& in_unit(std::string u) {
    unit = std::move(u);
    return *this;
  }
  Field& needed() {
    required = true;
    return *this;
  }
  Field& needed_when(std::string w) {
    required_when = std::move(w);
    return *this;
  }
  Field& items(int lo_n, int hi_n) {
    min_items = lo_n, max_items = hi_n;
    return *this;
  }
  Field& eg(nlohmann::json v) {
    example = std::move(v);
    return *this;
  }
};

// One JSON object of a document: its fields, in the order the reference lists them.
struct ObjectDoc {
  std::string title;    // "solver", "boundaries[]"
  std::string meaning;  // a sentence or two
  std::vector<Field> fields;
  bool free_keys =
      false;  // other keys are allowed too (a list design's point: scene paths), read with accept()
  const Field* find(const std::string& key) const;
};

Field number(std::string key, std::string meaning);
Field integer(std::string key, std::string meaning);
Field boolean(std::string key, std::string meaning);
Field string(std::string key, std::string meaning);
Field choice(std::string key, std::vector<std::string> choices, std::string meaning);
Field vector(std::string key, int min_items, int max_items, std::string meaning);
Field object(std::string key, const ObjectDoc& doc, std::string meaning);
Field object_array(std::string key, const ObjectDoc& doc, std::string meaning);
Field map(std::string key, nlohmann::json value_schema, std::string type_text, std::string meaning);
Field value(std::string key, nlohmann::json schema, std::string type_text, std::string meaning);

// "[0, 1]", "(0, inf)": a field's static range as messages and the reference write it.
std::string range_text(double lo, double hi, bool lo_open, bool hi_open);
// "[1, 1000000]": an integer field's range, written out in full.
std::string integer_range_text(double lo, double hi);
// A number as messages print it (shortest round-trip-ish form, "0.1", "1e+06").
std::string number_text(double v);

// The JSON Schema (draft 2020-12) of a document whose top-level object is `root`.
nlohmann::ordered_json json_schema(const ObjectDoc& root, const std::string& id, const std::string& title);
// The Markdown reference: `intro` (a paragraph), then a section and a table per object.
std::string markdown_reference(const ObjectDoc& root, const std::string& title, const std::string& intro,
                               const std::string& command);

// Every field reachable from `root` with its dotted path ("solver.dx", "boundaries.0.lo": arrays at index 0).
struct FieldAt {
  std::string path;
  const Field* field;
};
std::vector<FieldAt> all_fields(const ObjectDoc& root);

}  // namespace flume::input
