#include "common/input/fields.h"

#include <cmath>
#include <sstream>

namespace flume::input {

using json = nlohmann::json;

const Field* ObjectDoc::find(const std::string& key) const {
  for (const auto& f : fields)
    if (f.key == key) return &f;
  return nullptr;
}

namespace {
Field make(std::string key, FieldType type, std::string meaning) {
  Field f;
  f.key = std::move(key);
  f.type = type;
  f.meaning = std::move(meaning);
  return f;
}
}  // namespace

Field number(std::string key, std::string meaning) {
  return make(std::move(key), FieldType::kNumber, std::move(meaning));
}
Field integer(std::string key, std::string meaning) {
  return make(std::move(key), FieldType::kInteger, std::move(meaning));
}
Field boolean(std::string key, std::string meaning) {
  return make(std::move(key), FieldType::kBoolean, std::move(meaning));
}
Field string(std::string key, std::string meaning) {
  return make(std::move(key), FieldType::kString, std::move(meaning));
}
Field choice(std::string key, std::vector<std::string> choices, std::string meaning) {
  Field f = make(std::move(key), FieldType::kChoice, std::move(meaning));
  f.choices = std::move(choices);
  return f;
}
Field vector(std::string key, int min_items, int max_items, std::string meaning) {
  Field f = make(std::move(key), FieldType::kVector, std::move(meaning));
  return f.items(min_items, max_items);
}
Field object(std::string key, const ObjectDoc& doc, std::string meaning) {
  Field f = make(std::move(key), FieldType::kObject, std::move(meaning));
  f.object = &doc;
  return f;
}
Field object_array(std::string key, const ObjectDoc& doc, std::string meaning) {
  Field f = make(std::move(key), FieldType::kObjectArray, std::move(meaning));
  f.object = &doc;
  return f;
}
Field map(std::string key, json value_schema, std::string type_text, std::string meaning) {
  Field f = make(std::move(key), FieldType::kMap, std::move(meaning));
  f.value_schema = std::move(value_schema);
  f.type_text = std::move(type_text);
  return f;
}
Field value(std::string key, json schema, std::string type_text, std::string meaning) {
  Field f = make(std::move(key), FieldType::kValue, std::move(meaning));
  f.value_schema = std::move(schema);
  f.type_text = std::move(type_text);
  return f;
}

std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string integer_range_text(double lo, double hi) {
  auto text = [](double v) {
    return std::isfinite(v) ? std::to_string(static_cast<long long>(v)) : number_text(v);
  };
  return "[" + text(lo) + ", " + text(hi) + "]";
}

std::string range_text(double lo, double hi, bool lo_open, bool hi_open) {
  const std::string l = std::isinf(lo) ? "(-inf" : std::string(lo_open ? "(" : "[") + number_text(lo);
  const std::string h = std::isinf(hi) ? "inf)" : number_text(hi) + (hi_open ? ")" : "]");
  return l + ", " + h;
}

namespace {

bool has_range(const Field& f) { return std::isfinite(f.lo) || std::isfinite(f.hi); }

std::string description(const Field& f) {
  std::string d = f.meaning;
  if (!f.unit.empty()) d += " [" + f.unit + "]";
  if (!f.range_note.empty()) d += "; allowed: " + f.range_note;
  if (!f.default_note.empty()) d += "; default: " + f.default_note;
  if (!f.required_when.empty()) d += "; required " + f.required_when;
  return d;
}

using ojson = nlohmann::ordered_json;

ojson object_schema(const ObjectDoc& doc);
ojson ordered(const json& j) { return ojson::parse(j.dump()); }

ojson field_schema(const Field& f) {
  ojson s;
  switch (f.type) {
    case FieldType::kNumber:
    case FieldType::kInteger:
      s["type"] = f.type == FieldType::kNumber ? "number" : "integer";
      if (f.type == FieldType::kInteger) {
        if (std::isfinite(f.lo)) s["minimum"] = static_cast<long long>(f.lo);
        if (std::isfinite(f.hi)) s["maximum"] = static_cast<long long>(f.hi);
        break;
      }
      if (std::isfinite(f.lo)) s[f.lo_open ? "exclusiveMinimum" : "minimum"] = f.lo;
      if (std::isfinite(f.hi)) s[f.hi_open ? "exclusiveMaximum" : "maximum"] = f.hi;
      break;
    case FieldType::kBoolean:
      s["type"] = "boolean";
      break;
    case FieldType::kString:
      s["type"] = "string";
      break;
    case FieldType::kChoice:
      s["type"] = "string";
      s["enum"] = f.choices;
      break;
    case FieldType::kVector:
      s = {{"type", "array"},
           {"items", {{"type", "number"}}},
           {"minItems", f.min_items},
           {"maxItems", f.max_items}};
      break;
    case FieldType::kObject:
      s = object_schema(*f.object);
      break;
    case FieldType::kObjectArray:
      s = {{"type", "array"}, {"items", object_schema(*f.object)}};
      break;
    case FieldType::kMap:
      s = {{"type", "object"}, {"additionalProperties", ordered(f.value_schema)}};
      break;
    case FieldType::kValue:
      s = ordered(f.value_schema);
      break;
  }
  if (!f.default_value.is_null()) s["default"] = ordered(f.default_value);
  s["description"] = description(f);
  if (!f.unit.empty()) s["x-unit"] = f.unit;
  return s;
}

ojson object_schema(const ObjectDoc& doc) {
  ojson s = {{"type", "object"},
             {"description", doc.meaning},
             {"properties", ojson::object()},
             {"additionalProperties", false}};
  ojson required = ojson::array();
  for (const auto& f : doc.fields) {
    s["properties"][f.key] = field_schema(f);
    if (f.required) required.push_back(f.key);
  }
  if (!required.empty()) s["required"] = required;
  return s;
}

std::string cell(std::string text) {
  std::string out;
  for (char c : text) {
    if (c == '|')
      out += "\\|";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out;
}

std::string type_text(const Field& f, const std::string& child_path) {
  switch (f.type) {
    case FieldType::kNumber:
      return "number";
    case FieldType::kInteger:
      return "integer";
    case FieldType::kBoolean:
      return "boolean";
    case FieldType::kString:
      return "string";
    case FieldType::kChoice: {
      std::string s;
      for (const auto& c : f.choices) s += (s.empty() ? "" : " \\| ") + ("`" + c + "`");
      return "one of " + s;
    }
    case FieldType::kVector:
      return "array of " +
             (f.min_items == f.max_items ? std::to_string(f.min_items)
                                         : std::to_string(f.min_items) + "-" + std::to_string(f.max_items)) +
             " numbers";
    case FieldType::kObject:
      return "object, see `" + child_path + "`";
    case FieldType::kObjectArray:
      return "array of objects, see `" + child_path + "`";
    default:
      return cell(f.type_text);
  }
}

std::string allowed_text(const Field& f) {
  std::string s;
  if (f.type == FieldType::kNumber && has_range(f)) s = range_text(f.lo, f.hi, f.lo_open, f.hi_open);
  if (f.type == FieldType::kInteger && has_range(f)) s = integer_range_text(f.lo, f.hi);
  if (!f.range_note.empty()) s += (s.empty() ? "" : "; ") + f.range_note;
  return cell(s);
}

std::string default_text(const Field& f) {
  std::string s;
  if (!f.default_value.is_null()) s = "`" + f.default_value.dump() + "`";
  if (!f.default_note.empty()) s += (s.empty() ? "" : "; ") + f.default_note;
  return cell(s);
}

void markdown_object(const ObjectDoc& doc, const std::string& path, std::string& out,
                     std::vector<std::pair<const ObjectDoc*, std::string>>& queue) {
  out += "\n## `" + (path.empty() ? std::string("(top level)") : path) + "`\n\n";
  if (!doc.meaning.empty()) out += doc.meaning + "\n\n";
  out += "| field | type | required | default | allowed | unit | meaning |\n";
  out += "|---|---|---|---|---|---|---|\n";
  for (const auto& f : doc.fields) {
    std::string child = path.empty() ? f.key : path + "." + f.key;
    if (f.type == FieldType::kObjectArray) child += "[]";
    const std::string req = f.required ? "yes" : (f.required_when.empty() ? "" : cell(f.required_when));
    out += "| `" + f.key + "` | " + type_text(f, child) + " | " + req + " | " + default_text(f) + " | " +
           allowed_text(f) + " | " + cell(f.unit) + " | " + cell(f.meaning) + " |\n";
    if (f.type == FieldType::kObject || f.type == FieldType::kObjectArray)
      queue.emplace_back(f.object, child);
  }
}

void collect(const ObjectDoc& doc, const std::string& path, std::vector<FieldAt>& out) {
  for (const auto& f : doc.fields) {
    const std::string p = path.empty() ? f.key : path + "." + f.key;
    out.push_back({p, &f});
    if (f.type == FieldType::kObject) collect(*f.object, p, out);
    if (f.type == FieldType::kObjectArray) collect(*f.object, p + ".0", out);
  }
}

}  // namespace

nlohmann::ordered_json json_schema(const ObjectDoc& root, const std::string& id, const std::string& title) {
  ojson out = {{"$schema", "https://json-schema.org/draft/2020-12/schema"}, {"$id", id}, {"title", title}};
  const ojson body = object_schema(root);
  for (auto it = body.begin(); it != body.end(); ++it) out[it.key()] = *it;
  return out;
}

std::string markdown_reference(const ObjectDoc& root, const std::string& title, const std::string& intro,
                               const std::string& command) {
  std::string out = "# " + title + "\n\n<!-- Generated by `" + command +
                    "` from the field descriptions the parser reads with; do not edit by hand. -->\n\n" +
                    intro + "\n";
  // Breadth-first, so that each section follows the one that names it.
  std::vector<std::pair<const ObjectDoc*, std::string>> queue = {{&root, ""}};
  for (size_t i = 0; i < queue.size(); ++i) {
    const auto [doc, path] = queue[i];  // a copy: markdown_object appends to the queue
    markdown_object(*doc, path, out, queue);
  }
  return out;
}

std::vector<FieldAt> all_fields(const ObjectDoc& root) {
  std::vector<FieldAt> out;
  collect(root, "", out);
  return out;
}

}  // namespace flume::input
