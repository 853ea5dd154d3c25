// The field descriptions (common/input/fields.h) against the parsers that read with them: every described
// field is accepted by its parser, the parser cannot read a field its description lacks, and the references
// in docs/ are what `flume schema KIND --markdown` generates now (so they cannot drift from the code).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "calibration/spec.h"
#include "calibration/spec_fields.h"
#include "campaigns/spec.h"
#include "campaigns/spec_fields.h"
#include "cli/schema.h"
#include "common/errors.h"
#include "common/input/field_reader.h"
#include "solver/scene.h"
#include "solver/scene_fields.h"
#include "study/spec_fields.h"
#include "study/tradeoff.h"

namespace flume {
namespace {

using json = nlohmann::json;
const std::string kSource = FLUME_SOURCE_DIR;

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(FieldReader, ReadingAnUndescribedFieldIsAProgrammingError) {
  const input::ObjectDoc doc{"t", "", {input::number("x", "a number").in(0, 1).def(0.5)}};
  const json j = {{"x", 0.25}};
  input::FieldReader r(j, doc, "", "f.json");
  EXPECT_EQ(r.number("x"), 0.25);
  EXPECT_THROW(r.number("y"), std::logic_error);
  EXPECT_THROW(r.accept("y"), std::logic_error);
  EXPECT_THROW(r.string("x"), std::logic_error);  // read as another type than described
}

TEST(FieldReader, MessagesNameFileFieldAndAllowedRange) {
  const input::ObjectDoc doc{"t",
                             "",
                             {input::number("x", "a number").above(0).at_most(1).needed(),
                              input::choice("c", {"a", "b"}, "a choice").def("a")}};
  auto message = [&](const json& j, auto read) {
    try {
      input::FieldReader r(j, doc, "sec", "f.json");
      read(r);
      r.finish();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message(json::object(), [](auto& r) { r.number("x"); }),
            "f.json: sec.x: is required (a number in (0, 1])");
  EXPECT_EQ(message(json{{"x", 2}}, [](auto& r) { r.number("x"); }),
            "f.json: sec.x: must be in (0, 1] (got 2)");
  EXPECT_EQ(message(json{{"x", "2"}}, [](auto& r) { r.number("x"); }),
            "f.json: sec.x: must be a number in (0, 1], got a string");
  EXPECT_EQ(message(json{{"x", 1}, {"c", "z"}}, [](auto& r) { r.number("x"), r.choice("c"); }),
            "f.json: sec.c: must be one of a|b (got 'z')");
  EXPECT_EQ(message(json{{"x", 1}, {"cc", "a"}}, [](auto& r) { r.number("x"), r.choice("c"); }),
            "f.json: sec.cc: unknown field (known here: c, x)");
}

// Values the description allows, for a field the base documents lack.
std::vector<json> valid_values(const input::Field& f) {
  std::vector<json> out;
  if (!f.example.is_null()) out.push_back(f.example);
  if (!f.default_value.is_null()) out.push_back(f.default_value);
  if (f.type == input::FieldType::kChoice) out.push_back(f.choices.front());
  if (f.type == input::FieldType::kObject) out.push_back(json::object());
  if (f.type == input::FieldType::kVector)
    for (int n = f.min_items; n <= f.max_items; ++n)
      out.push_back(std::vector<double>(static_cast<size_t>(n), 0.0));
  return out;
}

// Every field `doc` lists is accepted by its parser: in a base document that has it, or set (to its example,
// default, first choice, an empty object, zeros) in one whose enclosing object exists or can be created. A
// field described but never read fails as "unknown field"; a field read but not described cannot be accepted
// (the logic_error above). `accepts` parses a document and says why not.
void expect_every_field_accepted(const input::ObjectDoc& doc, const std::vector<json>& bases,
                                 const std::function<std::string(const json&)>& refusal) {
  std::vector<std::string> refused;
  for (const auto& [path, field] : input::all_fields(doc)) {
    std::string pointer = "/" + path;
    for (auto& c : pointer) c = c == '.' ? '/' : c;
    const json::json_pointer ptr(pointer);
    std::string last = "no base document has its enclosing object";
    bool accepted = false;
    for (const json& base : bases) {
      const bool parent =
          base.contains(ptr.parent_pointer()) ||
          (!ptr.parent_pointer().empty() && base.contains(ptr.parent_pointer().parent_pointer()) &&
           !std::isdigit(static_cast<unsigned char>(ptr.parent_pointer().back()[0])));
      if (!base.contains(ptr) && !parent) continue;
      std::vector<json> values = {json()};  // null: the base's own value
      if (!base.contains(ptr)) values = valid_values(*field);
      for (const json& v : values) {
        json d = base;
        if (!v.is_null()) d[ptr] = v;
        const std::string why = refusal(d);
        accepted = why.empty();
        if (!accepted) last = why;
        if (accepted) break;
      }
      if (accepted) break;
    }
    if (!accepted) refused.push_back(path + " (" + last + ")");
  }
  std::string list;
  for (const auto& r : refused) list += "\n  " + r;
  EXPECT_TRUE(refused.empty()) << "described but refused by the " << doc.title << " parser:" << list;
}

TEST(SceneSchema, EveryDescribedFieldIsAcceptedByTheParser) {
  std::vector<json> bases;
  for (const char* f :
       {"scenes/debris/bore_container.json", "scenes/dam_break/martin_moyce_2d.json",
        "scenes/waseda/waseda_2d.json", "scenes/waseda/waseda_3d.json", "scenes/waseda/waseda_3d_half.json",
        "scenes/waseda/waseda_apron.json", "scenes/debris/grounding_sheet.json",
        "tests/schema/box_boundary_2d.json", "tests/schema/basin_debris_3d.json",
        "tests/schema/probe_on_boundary_2d.json"})
    bases.push_back(json::parse(slurp(kSource + "/" + f)));
  expect_every_field_accepted(scene_doc(), bases, [](json d) -> std::string {
    // An inflow record is given at run time (--set inflow.record=RUN/result.h5): named here, so that the only
    // error the apron scene may raise is that the record cannot be read, after every field was checked.
    if (d.contains("inflow") && !d["inflow"].contains("record")) d["inflow"]["record"] = "RUN/result.h5";
    try {
      parse_scene_text(d.dump(), "base.json");
    } catch (const InputError& e) {
      const bool record_only = d.contains("inflow") && e.field() == "inflow.record" &&
                               e.problem().find("unknown field") == std::string::npos;
      return record_only ? "" : e.what();
    }
    return "";
  });
}

TEST(CampaignSchema, EveryDescribedFieldIsAcceptedByTheParser) {
  const std::string u = R"({"type": "uniform", "lower": 0, "upper": 1})";
  std::vector<json> bases;
  for (
      const std::string& text : std::vector<std::string>{
          // each distribution type as parameters.0, each design type, correlation, run, overrides
          R"({"name": "a", "description": "d", "model": "ishigami", "overrides": {"x3": 0.5},
               "parameters": [{"path": "x1", "distribution": )" +
              u + R"(},
                              {"path": "x2", "distribution": {"type": "normal", "mean": 0, "std": 1}}],
               "correlation": [{"parameters": ["x1", "x2"], "rank": 0.3}],
               "design": {"type": "lhs", "samples": 4}, "seed": 1,
               "run": {"time_limit_s": 60, "threads": 1, "memory_limit_mb": 0, "output_dir": "", "checkpoint_every_s": 0}})",
          R"({"name": "b", "model": "ishigami", "parameters": [{"path": "x1", "distribution": {"type": "normal", "mean": 0, "std": 1}}],
               "design": {"type": "saltelli", "samples": 2, "base": "sobol"}, "seed": 1})",
          R"({"name": "c", "model": "ishigami", "parameters": [{"path": "x1", "distribution": {"type": "lognormal", "mu_log": 0, "sigma_log": 0.5}}],
               "design": {"type": "grid", "levels": 2}, "seed": 1})",
          R"({"name": "d", "model": "ishigami", "parameters": [{"path": "x1", "distribution": {"type": "beta", "alpha": 2, "beta": 2, "lower": 0, "upper": 1}}],
               "design": {"type": "one_at_a_time"}, "seed": 1})",
          R"({"name": "e", "model": "ishigami", "parameters": [{"path": "x1", "distribution": {"type": "choice", "values": [1, 2], "weights": [1, 1]}}],
               "design": {"type": "monte_carlo", "samples": 2}, "seed": 1})",
          R"({"name": "f", "model": "ishigami", "parameters": [{"path": "x1", "distribution": {"type": "truncated_normal", "mean": 0, "std": 1, "lower": -1, "upper": 1}}],
               "design": {"type": "sobol", "samples": 2}, "seed": 1})",
          R"({"name": "g", "model": "ishigami", "design": {"type": "list", "points": [{"label": "p", "x1": 1}, {"label": "q", "x1": 2}]}})",
          R"({"name": "h", "scene": "tests/schema/box_boundary_2d.json",
               "parameters": [{"path": "solver.cfl", "distribution": {"type": "uniform", "lower": 0.3, "upper": 0.4}}],
               "design": {"type": "monte_carlo", "samples": 2}, "seed": 1})"})
    bases.push_back(json::parse(text));
  expect_every_field_accepted(campaigns::campaign_doc(), bases, [](const json& d) -> std::string {
    try {
      campaigns::parse_campaign_spec(d.dump(), "spec.json", kSource);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  });
}

TEST(CalibrationSchema, EveryDescribedFieldIsAcceptedByTheParser) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("flume_test_schema_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "wg1.csv") << "time_s,WG1\n0,0\n1,0.05\n2,0\n";
  std::ofstream(dir / "g1.csv") << "time_s,G1\n0,0\n0.05,0\n0.1,0\n";
  const std::string params =
      R"([{"path": "reservoir.forcing.t99_s", "scale": "linear", "lower": 0.05, "upper": 2, "start": 0.2},
                                  {"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.12}])";
  std::vector<json> bases;
  for (const std::string& text : std::vector<std::string>{
           R"({"name": "a", "description": "d", "model": "gauge", "overrides": {}, "parameters": )" + params +
               R"(,
               "objective": {"window": [0, 2], "peak_weight": 1, "arrival_weight_m_per_s": 1, "arrival_threshold_m": 0.005,
                             "time_shift": {"lower": -0.1, "upper": 0.1, "start": 0}},
               "algorithm": {"name": "MLSL", "local": "SBPLX", "polish": "BOBYQA", "max_evaluations": 5,
                             "polish_evaluations": 5, "max_time_s": 0, "xtol_abs": 1e-4, "ftol_abs": 0,
                             "initial_step": 0.1, "population": 0, "seed": 1},
               "starts": [{"reservoir.forcing.t99_s": 0.3}], "multi_start": {"random": 1, "seed": 1},
               "profile": {"points": 2, "span": 0.1}, "run": {"time_limit_s": 60, "threads": 1, "output_dir": ""},
               "targets": [{"file": "wg1.csv", "weight": 1, "gauge": "WG1"}]})",
           R"({"name": "b", "model": "gauge", "parameters": )" + params +
               R"(, "objective": {"window": [0, 2]},
               "algorithm": {"name": "SBPLX", "max_evaluations": 5}, "targets": [{"file": "wg1.csv", "gauges": {"WG1": "WG1"}}]})",
           R"({"name": "c", "scene": ")" + kSource + R"(/tests/schema/box_boundary_2d.json",
               "parameters": [{"path": "solver.cfl", "scale": "log", "lower": 0.3, "upper": 0.5, "start": 0.4}],
               "objective": {"window": [0, 0.1]}, "algorithm": {"name": "SBPLX", "max_evaluations": 5},
               "targets": [{"file": "g1.csv"}]})"})
    bases.push_back(json::parse(text));
  expect_every_field_accepted(calibration::calibration_doc(), bases, [&](const json& d) -> std::string {
    try {
      calibration::parse_calibration_spec(d.dump(), "spec.json", dir.string());
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  });
  std::filesystem::remove_all(dir);
}

TEST(StudySchema, EveryDescribedFieldIsAcceptedByTheParser) {
  std::vector<json> bases;
  for (const auto& entry : std::filesystem::directory_iterator(kSource + "/scenes/studies"))
    if (entry.path().extension() == ".json") bases.push_back(json::parse(slurp(entry.path().string())));
  ASSERT_FALSE(bases.empty());
  expect_every_field_accepted(study::study_doc(), bases, [](const json& d) -> std::string {
    try {
      study::parse_tradeoff_spec(d.dump(), "spec.json", kSource + "/scenes/studies");
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  });
}

// docs/scene.md (and each spec's reference) is what `flume schema KIND --markdown` prints now; regenerate
// with scripts/schema-docs after changing a description.
TEST(SchemaDocs, ReferencesInDocsAreGeneratedFromTheDescriptions) {
  for (const auto& kind : cli::document_kinds()) {
    const std::string file = kSource + "/" + kind.reference;
    EXPECT_EQ(slurp(file), cli::markdown_text(kind))
        << file << " differs from `flume schema " << kind.name << " --markdown`: run scripts/schema-docs";
  }
}

}  // namespace
}  // namespace flume
