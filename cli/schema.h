// `flume schema DOCUMENT [--markdown]`: the JSON Schema (draft 2020-12) of a scene, campaign, calibration or
// study file, or its Markdown reference (docs/scene.md, ...), both generated from the field descriptions the
// parsers read with (common/input/fields.h).
#pragma once
#include <string>
#include <vector>

#include "common/input/fields.h"

namespace CLI {
class App;
}

namespace flume::cli {

struct DocumentKind {
  const char* name;                  // "scene"
  const input::ObjectDoc& (*doc)();  // its top-level object
  const char* title;                 // the reference's title
  const char* intro;                 // its first paragraph
  const char* reference;             // where the reference lives in the repository ("docs/scene.md")
};

const std::vector<DocumentKind>& document_kinds();
const DocumentKind& document_kind(const std::string& name);  // throws std::out_of_range when unknown

std::string schema_text(const DocumentKind& kind);    // the JSON Schema, indented, with a final newline
std::string markdown_text(const DocumentKind& kind);  // the reference

void add_schema_command(CLI::App& app);

}  // namespace flume::cli
