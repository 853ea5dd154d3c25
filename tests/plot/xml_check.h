// A minimal XML well-formedness checker for the plot tests only: one root element, matched tags, quoted
// attributes without '<', '&' only as a known or numeric entity, and the elements in document order so tests
// can look at attributes. Enough for the subset of XML an SVG writer emits; not a general parser.
#pragma once
#include <cctype>
#include <map>
#include <string>
#include <vector>

namespace flume::plot::test {

struct Element {
  std::string name;
  std::map<std::string, std::string> attrs;  // raw (still escaped) values
  std::string text;                          // raw text directly inside, tags stripped
};

struct XmlCheck {
  std::string error;  // empty when well-formed
  std::vector<Element> elements;
};

inline bool valid_entity(const std::string& s, std::size_t amp, std::size_t& end) {
  end = s.find(';', amp);
  if (end == std::string::npos || end - amp > 10) return false;
  std::string name = s.substr(amp + 1, end - amp - 1);
  if (name == "amp" || name == "lt" || name == "gt" || name == "quot" || name == "apos") return true;
  if (name.size() > 1 && name[0] == '#') {
    std::size_t i = 1;
    bool hex = name[1] == 'x';
    if (hex) ++i;
    if (i >= name.size()) return false;
    for (; i < name.size(); ++i)
      if (!(hex ? std::isxdigit(static_cast<unsigned char>(name[i]))
                : std::isdigit(static_cast<unsigned char>(name[i]))))
        return false;
    return true;
  }
  return false;
}

inline bool check_chars(const std::string& s, std::size_t from, std::size_t to, bool in_attr,
                        std::string& error) {
  for (std::size_t i = from; i < to; ++i) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    if (c == '<') return error = "stray '<' at " + std::to_string(i), false;
    if (in_attr && c == '"') return error = "'\"' inside attribute at " + std::to_string(i), false;
    if (c < 0x20 && c != '\t' && c != '\n' && c != '\r')
      return error = "control character at " + std::to_string(i), false;
    if (c == '&') {
      std::size_t end;
      if (!valid_entity(s, i, end)) return error = "bad entity at " + std::to_string(i), false;
      i = end;
    }
  }
  return true;
}

inline XmlCheck check_xml(const std::string& s) {
  XmlCheck r;
  std::vector<std::size_t> stack;  // indices into r.elements
  bool root_seen = false;
  std::size_t i = 0;
  auto name_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == ':' || c == '.';
  };
  while (i < s.size()) {
    std::size_t lt = s.find('<', i);
    std::size_t text_end = lt == std::string::npos ? s.size() : lt;
    if (!check_chars(s, i, text_end, false, r.error)) return r;
    std::string text = s.substr(i, text_end - i);
    if (stack.empty()) {
      for (char c : text)
        if (!std::isspace(static_cast<unsigned char>(c))) return r.error = "text outside the root element", r;
    } else {
      r.elements[stack.back()].text += text;
    }
    if (lt == std::string::npos) break;
    if (s.compare(lt, 4, "<!--") == 0) {
      std::size_t end = s.find("-->", lt);
      if (end == std::string::npos) return r.error = "unterminated comment", r;
      i = end + 3;
      continue;
    }
    if (s.compare(lt, 2, "<?") == 0 || s.compare(lt, 2, "<!") == 0) {
      if (root_seen) return r.error = "declaration after the root element", r;
      std::size_t end = s.find('>', lt);
      if (end == std::string::npos) return r.error = "unterminated declaration", r;
      i = end + 1;
      continue;
    }
    std::size_t p = lt + 1;
    bool closing = p < s.size() && s[p] == '/';
    if (closing) ++p;
    std::size_t n0 = p;
    while (p < s.size() && name_char(s[p])) ++p;
    std::string name = s.substr(n0, p - n0);
    if (name.empty()) return r.error = "empty tag name at " + std::to_string(lt), r;
    if (closing) {
      while (p < s.size() && std::isspace(static_cast<unsigned char>(s[p]))) ++p;
      if (p >= s.size() || s[p] != '>') return r.error = "bad closing tag " + name, r;
      if (stack.empty() || r.elements[stack.back()].name != name)
        return r.error = "closing </" + name + "> does not match", r;
      stack.pop_back();
      i = p + 1;
      continue;
    }
    if (stack.empty() && root_seen) return r.error = "second root element <" + name + ">", r;
    root_seen = true;
    Element e;
    e.name = name;
    bool self_closing = false;
    while (true) {
      std::size_t ws = p;
      while (p < s.size() && std::isspace(static_cast<unsigned char>(s[p]))) ++p;
      if (p >= s.size()) return r.error = "unterminated tag <" + name + ">", r;
      if (s[p] == '>') {
        ++p;
        break;
      }
      if (s.compare(p, 2, "/>") == 0) {
        self_closing = true;
        p += 2;
        break;
      }
      if (p == ws) return r.error = "attributes of <" + name + "> not separated", r;
      std::size_t a0 = p;
      while (p < s.size() && name_char(s[p])) ++p;
      std::string attr = s.substr(a0, p - a0);
      if (attr.empty() || p + 1 >= s.size() || s[p] != '=' || (s[p + 1] != '"' && s[p + 1] != '\''))
        return r.error = "bad attribute in <" + name + "> at " + std::to_string(a0), r;
      char q = s[p + 1];
      std::size_t v0 = p + 2, v1 = s.find(q, v0);
      if (v1 == std::string::npos) return r.error = "unterminated attribute " + attr, r;
      if (!check_chars(s, v0, v1, q == '"', r.error)) return r;
      if (e.attrs.count(attr)) return r.error = "duplicate attribute " + attr + " in <" + name + ">", r;
      e.attrs[attr] = s.substr(v0, v1 - v0);
      p = v1 + 1;
    }
    r.elements.push_back(std::move(e));
    if (!self_closing) stack.push_back(r.elements.size() - 1);
    i = p;
  }
  if (!stack.empty()) return r.error = "unclosed <" + r.elements[stack.back()].name + ">", r;
  if (!root_seen) return r.error = "no root element", r;
  return r;
}

}  // namespace flume::plot::test
