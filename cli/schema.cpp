#include "cli/schema.h"

#include <cstdio>
#include <memory>
#include <stdexcept>

#include "calibration/spec_fields.h"
#include "campaigns/spec_fields.h"
#include "common/command.h"
#include "solver/scene_fields.h"
#include "study/spec_fields.h"

namespace flume::cli {

const std::vector<DocumentKind>& document_kinds() {
  static const std::vector<DocumentKind> kinds = {
      {"scene", scene_doc, "Scene file reference",
       "A scene is one JSON object: what a run simulates (`flume run SCENE.json`, `flume check SCENE.json`). "
       "Every field below is checked when the scene is read; a bad value is reported as one line naming the "
       "file, the field and the allowed range, and an unknown field is refused. Any value can be overridden "
       "with `--set path=value` (array elements by index: `--set water.0.hi.1=0.6`). Lengths in m, times in "
       "s, "
       "SI throughout; 2D scenes use (x, z), 3D ones (x, y, z), the last axis vertical. Ranges in the "
       "`allowed` "
       "column are static; where a bound follows from other fields it says so. `flume schema scene` prints "
       "the "
       "same as a JSON Schema (draft 2020-12).",
       "docs/scene.md"},
      {"campaign", campaigns::campaign_doc, "Campaign spec reference",
       "A campaign spec is one JSON object: sampled runs of a scene or an analytic model, kept in an SQLite "
       "database (`flume campaign run SPEC --db FILE`, docs/campaigns.md). Every field below is checked "
       "before the "
       "database is touched; a bad value is reported as one line naming the file, the field and the allowed "
       "range, and an unknown field is refused. Parameter paths and overrides are scene fields "
       "(docs/scene.md), "
       "checked against the scene at every design point. `flume schema campaign` prints the same as a JSON "
       "Schema (draft 2020-12).",
       "docs/campaign-spec.md"},
      {"calibration", calibration::calibration_doc, "Calibration spec reference",
       "A calibration spec is one JSON object: scene parameters fitted by NLopt to measured gauge records "
       "(`flume calibrate SPEC --db FILE --out DIR`, docs/calibration.md). Every field below is checked "
       "before "
       "anything runs; a bad value is reported as one line naming the file, the field and the allowed range, "
       "and "
       "an unknown field is refused. Parameter paths and overrides are scene fields (docs/scene.md), checked "
       "against the scene at each parameter's bounds and start. `flume schema calibration` prints the same "
       "as a "
       "JSON Schema (draft 2020-12).",
       "docs/calibration-spec.md"},
      {"study", study::study_doc, "Study spec reference",
       "A study spec is one JSON object: fidelity settings of one scene (dx, ppc, precision, variant scenes, "
       "...) "
       "run as a campaign with a list design, each compared with a reference (`flume study tradeoff SPEC "
       "--db "
       "FILE`, docs/tradeoff.md). Every field below is checked before anything runs; a bad value is reported "
       "as "
       "one line naming the file, the field and the allowed range, and an unknown field is refused. A "
       "setting's "
       "paths are scene fields (docs/scene.md), checked against the scene. `flume schema study` prints the "
       "same as "
       "a JSON Schema (draft 2020-12).",
       "docs/study-spec.md"},
  };
  return kinds;
}

const DocumentKind& document_kind(const std::string& name) {
  for (const auto& k : document_kinds())
    if (name == k.name) return k;
  throw std::out_of_range("no document kind " + name);
}

std::string schema_text(const DocumentKind& kind) {
  return input::json_schema(kind.doc(), std::string("https://flume.invalid/schema/") + kind.name + ".json",
                            std::string("flume ") + kind.name + " file")
             .dump(2) +
         "\n";
}

std::string markdown_text(const DocumentKind& kind) {
  return input::markdown_reference(kind.doc(), kind.title, kind.intro,
                                   std::string("flume schema ") + kind.name + " --markdown");
}

void add_schema_command(CLI::App& app) {
  struct Args {
    std::string kind;
    bool markdown = false;
  };
  auto a = std::make_shared<Args>();
  std::vector<std::string> names;
  for (const auto& k : document_kinds()) names.push_back(k.name);
  app.add_option("DOCUMENT", a->kind, "which file: scene, campaign, calibration or study")
      ->required()
      ->check(CLI::IsMember(names));
  app.add_flag("--markdown", a->markdown, "print the Markdown reference (docs/) instead of the JSON Schema");
  on_parse(app, [a]() -> int {
    const DocumentKind& k = document_kind(a->kind);
    const std::string text = a->markdown ? markdown_text(k) : schema_text(k);
    std::fwrite(text.data(), 1, text.size(), stdout);
    return kExitOk;
  });
}

}  // namespace flume::cli
