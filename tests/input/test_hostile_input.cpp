// Hostile documents against every parser (issue 29): each is refused as one InputError naming the file and
// the field, never a crash, an unbounded allocation or an "internal error". The cases use only the parsers'
// public entry points, so they run unchanged against older code (where they crash or fail).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "calibration/records.h"
#include "calibration/spec.h"
#include "campaigns/spec.h"
#include "common/errors.h"
#include "solver/scene.h"
#include "study/tradeoff.h"

namespace flume {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/waseda_2d.json";

std::string nested(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

// Runs `parse` and expects an InputError whose message holds every fragment.
template <class Parse>
void expect_input_error(Parse parse, const std::vector<std::string>& fragments) {
  try {
    parse();
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << f << " in: " << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an input error: " << e.what();
  }
}

// One parser's entry point on a document's text.
using TextParser = std::function<void(const std::string& text, const std::string& label)>;

std::vector<std::pair<std::string, TextParser>> parsers() {
  return {
      {"scene", [](const std::string& t, const std::string& l) { parse_scene_text(t, l); }},
      {"campaign", [](const std::string& t, const std::string& l) { campaigns::parse_campaign_spec(t, l, "."); }},
      {"calibration",
       [](const std::string& t, const std::string& l) { calibration::parse_calibration_spec(t, l, "."); }},
      {"study", [](const std::string& t, const std::string& l) { study::parse_tradeoff_spec(t, l, "."); }},
  };
}

TEST(HostileInput, DeepNestingIsRefusedNotACrash) {
  // 60,000 levels crashed `flume check` (the document was dumped recursively before it was checked).
  for (const auto& entry : parsers()) {
    SCOPED_TRACE(entry.first);
    const TextParser& parse = entry.second;
    expect_input_error([&] { parse(nested(60000), "deep.json"); }, {"deep.json", "nested deeper than 64"});
    expect_input_error([&] { parse("{\"name\": " + nested(100) + "}", "deep.json"); },
                       {"deep.json: name", "nested deeper than 64"});
  }
}

TEST(HostileInput, NumberOverflowNamesTheField) {
  for (const auto& entry : parsers()) {
    SCOPED_TRACE(entry.first);
    const TextParser& parse = entry.second;
    expect_input_error([&] { parse(R"({"name": "x", "solver": {"dx": 1e999}})", "big.json"); },
                       {"big.json: solver.dx: ", "out of range"});
    expect_input_error([&] { parse(R"({"water": [{"lo": [0.1, -1e999]}]})", "big.json"); },
                       {"big.json: water.0.lo.1: ", "out of range"});
  }
}

TEST(HostileInput, TopLevelMustBeAnObject) {
  for (const auto& entry : parsers()) {
    SCOPED_TRACE(entry.first);
    const TextParser& parse = entry.second;
    for (const char* doc : {"[1, 2]", "null", "3", "\"scene\""})
      expect_input_error([&] { parse(doc, "top.json"); }, {"top.json: ", "not an object"});
  }
}

TEST(HostileInput, LongStringsAndArraysAreBounded) {
  for (const auto& entry : parsers()) {
    SCOPED_TRACE(entry.first);
    const TextParser& parse = entry.second;
    expect_input_error([&] { parse("{\"name\": \"" + std::string(1 << 20, 'n') + "\"}", "long.json"); },
                       {"long.json: name: ", "at most 4096"});
    std::string many = "{\"water\": [";
    for (int i = 0; i < 100001; ++i) many += i ? ",0" : "0";
    expect_input_error([&] { parse(many + "]}", "many.json"); }, {"many.json: water", "at most 100000"});
  }
}

// `--set` paths and plain-string values become JSON keys and strings: invalid UTF-8 in them ended as
// "internal error: invalid UTF-8 byte" (found by tests/fuzz/fuzz_set).
TEST(HostileInput, OverridesMustBeUtf8) {
  const std::string scene = read_scene_file(kScene);
  expect_input_error([&] { parse_scene_text(scene, "w.json", {parse_override("reservo\xff.t99_s=1")}); },
                     {"w.json", "not valid UTF-8"});
  expect_input_error([&] { parse_scene_text(scene, "w.json", {parse_override("name=\xff\xfe")}); },
                     {"w.json", "name: ", "not valid UTF-8"});
}

class HostileFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("flume_hostile_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  fs::path dir_;
};

// A device in place of a file allocated until bad_alloc: the loaders read regular files only, of bounded size.
TEST_F(HostileFiles, DevicesAndFoldersAreNotRead) {
  expect_input_error([] { load_scene("/dev/zero"); }, {"/dev/zero", "regular file"});
  expect_input_error([&] { load_scene(dir_.string()); }, {"regular file"});
  expect_input_error([] { campaigns::load_campaign_spec("/dev/zero"); }, {"/dev/zero", "regular file"});
  expect_input_error([] { calibration::load_calibration_spec("/dev/zero"); }, {"/dev/zero", "regular file"});
  expect_input_error([] { study::load_tradeoff_spec("/dev/zero"); }, {"/dev/zero", "regular file"});
  expect_input_error([] { calibration::read_target_csv("/dev/zero", {}, {"WG1"}, 0, 1, 1, "targets.0"); },
                     {"/dev/zero", "regular file"});
  // A spec whose scene is a device.
  const std::string spec = write("dev.json", R"({"name": "dev", "scene": "/dev/zero",
      "parameters": [{"path": "solver.dx", "distribution": {"type": "uniform", "lower": 0.02, "upper": 0.04}}],
      "design": {"type": "monte_carlo", "samples": 2}, "seed": 1})");
  expect_input_error([&] { campaigns::load_campaign_spec(spec); }, {"/dev/zero", "regular file"});
}

TEST_F(HostileFiles, OversizedFilesAreRefusedBeforeReading) {
  // A 10 MB name: refused by the file's size, with the allowed size.
  const std::string big = write("big.json", "{\"name\": \"" + std::string(10 << 20, 'n') + "\"}");
  expect_input_error([&] { load_scene(big); }, {big, "at most 4194304"});
  expect_input_error([&] { campaigns::load_campaign_spec(big); }, {big, "at most 4194304"});
  // 250,000 water boxes.
  std::string boxes = "{\"water\": [";
  for (int i = 0; i < 250000; ++i) boxes += std::string(i ? "," : "") + R"({"lo": [0.1, 0.1], "hi": [0.3, 0.3]})";
  const std::string many = write("many.json", boxes + "]}");
  expect_input_error([&] { load_scene(many); }, {many, "at most 4194304"});
}

TEST_F(HostileFiles, TargetCsvColumnsAreBounded) {
  std::string header = "time_s";
  for (int c = 0; c < 5000; ++c) header += ",WG" + std::to_string(c);
  const std::string csv = write("wide.csv", header + "\n0" + std::string(5000, ',') + "\n");
  expect_input_error([&] { calibration::read_target_csv(csv, {}, {"WG1"}, 0, 1, 1, "targets.0"); },
                     {csv, "line 1", "at most 1000"});
}

// The example spec of docs/campaigns.md parses as documented (it said "correlations"; the field is
// "correlation").
TEST(DocumentedExamples, CampaignSpecParses) {
  std::ifstream in(std::string(FLUME_SOURCE_DIR) + "/docs/campaigns.md");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string doc = ss.str();
  const auto at = doc.find("```json", doc.find("## The spec"));
  ASSERT_NE(at, std::string::npos);
  const auto from = doc.find('\n', at) + 1;
  const std::string spec = doc.substr(from, doc.find("```", from) - from);
  const campaigns::CampaignSpec c = campaigns::parse_campaign_spec(spec, "docs/campaigns.md", FLUME_SOURCE_DIR);
  EXPECT_EQ(c.name, "friction-mc");
  EXPECT_EQ(c.points.values.size(), 64u);
}

}  // namespace
}  // namespace flume
