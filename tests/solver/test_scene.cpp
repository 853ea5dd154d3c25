// Scene validation through the real command line (issue 2, item 7): every malformed scene is rejected by
// `flume check` and `flume run` with exit code 2 and exactly one line on stderr that names the file, the
// field path and what is allowed. Also the `--set` contract: a value is JSON where it parses as JSON, a
// string otherwise, and overrides change the scene.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/errors.h"
#include "solver/scene.h"
#include "store/h5/run_file.h"
#include "test_util.h"

namespace flume {
namespace {

namespace fs = std::filesystem;

// A valid 2D scene; the cases below break one thing in it.
const char* kValid = R"({
  "name": "valid",
  "dimension": 2,
  "domain": {"lo": [0.0, 0.0], "hi": [1.0, 0.5], "walls": "slip"},
  "solver": {"dx": 0.02, "ppc": 4, "cfl": 0.4, "precision": "double", "end_time": 0.01},
  "fluid": {"bulk_modulus": 2.0e6, "gamma": 7.0, "viscosity": 1.0e-3, "jbar_psi": 0.5},
  "water": [{"lo": [0.1, 0.1], "hi": [0.3, 0.3]}],
  "boundaries": [{"name": "floor", "type": "half_space", "point": [0.0, 0.1], "normal": [0.0, 1.0],
                  "condition": "slip"}],
  "instruments": {"gauges": [{"name": "g1", "position": [0.2]}],
                  "loads": [{"name": "floor_load", "boundary": "floor"}]}
})";

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << "test bug: '" << from << "' not in the valid scene";
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

struct CliResult {
  int rc = -1;
  std::string out, err;
};

class SceneCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("flume_test_scene_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  // Runs `flume ARGS`, capturing stdout and stderr.
  CliResult flume(const std::string& args) {
    CliResult r;
    const std::string out = (dir_ / "stdout.txt").string(), err = (dir_ / "stderr.txt").string();
    r.rc = test::run_command(std::string(FLUME_EXE) + " " + args + " >" + out + " 2>" + err);
    r.out = test::read_text(out);
    r.err = test::read_text(err);
    return r;
  }

  // The scene file must fail `check` and `run` alike with exit code 2 and a single stderr line holding
  // the file, the field path and every `allowed` fragment.
  void expect_file_rejected(const std::string& file, const std::string& sets, const std::string& field,
                            const std::vector<std::string>& allowed) {
    const std::string out_dir = (dir_ / "out").string();
    const std::vector<std::string> commands = {"check " + file + sets,
                                               "run " + file + " --out " + out_dir + sets};
    for (const std::string& cmd : commands) {
      SCOPED_TRACE("flume " + cmd);
      const CliResult r = flume(cmd);
      EXPECT_EQ(r.rc, kExitInvalidInput) << r.err;
      ASSERT_FALSE(r.err.empty());
      EXPECT_EQ(r.err.back(), '\n');
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "stderr must be exactly one line:\n"
                                                                 << r.err;
      EXPECT_NE(r.err.find(file), std::string::npos) << "the message must name the file:\n" << r.err;
      if (!field.empty()) {
        EXPECT_NE(r.err.find(": " + field + ": "), std::string::npos) << "field path:\n" << r.err;
      }
      for (const auto& a : allowed)
        EXPECT_NE(r.err.find(a), std::string::npos) << "'" << a << "' in:\n" << r.err;
      EXPECT_FALSE(fs::exists(out_dir + "/result.h5")) << "an invalid scene must not produce a result";
      EXPECT_FALSE(fs::exists(out_dir + "/run.json"));
    }
  }
  void expect_rejected(const std::string& name, const std::string& text, const std::string& field,
                       const std::vector<std::string>& allowed) {
    expect_file_rejected(write(name, text), "", field, allowed);
  }

  fs::path dir_;
};

TEST_F(SceneCli, ValidSceneIsAcceptedByCheckAndRun) {
  const std::string file = write("valid.json", kValid);
  const CliResult c = flume("check " + file);
  EXPECT_EQ(c.rc, kExitOk) << c.err;
  EXPECT_TRUE(c.err.empty()) << c.err;
  const CliResult r = flume("run " + file + " --out " + (dir_ / "out").string() + " --quiet");
  EXPECT_EQ(r.rc, kExitOk) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "out" / "result.h5"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "run.json"));
}

// A run's outputs say what it ran: the scene with the --set overrides applied, in run.json and result.h5.
TEST_F(SceneCli, RunRecordsTheSceneWithItsOverrides) {
  const std::string file = write("valid.json", kValid);
  const fs::path out = dir_ / "out_set";
  const CliResult r = flume("run " + file + " --out " + out.string() + " --quiet --set solver.end_time=0.005");
  ASSERT_EQ(r.rc, kExitOk) << r.err;
  const auto run = nlohmann::json::parse(test::read_text((out / "run.json").string()));
  ASSERT_TRUE(run.contains("scene_json"));
  EXPECT_DOUBLE_EQ(run["scene_json"]["solver"]["end_time"].get<double>(), 0.005);
  EXPECT_EQ(run["scene_json"]["dimension"].get<int>(), 2);
  const auto h5 = nlohmann::json::parse(h5::Reader((out / "result.h5").string()).string_attribute("/", "scene_json"));
  EXPECT_EQ(h5, run["scene_json"]);
}

TEST_F(SceneCli, MissingRequiredField) {
  expect_rejected("missing_dimension.json", replace(kValid, R"("dimension": 2,)", ""), "dimension",
                  {"is required", "[2, 3]"});
  expect_rejected("missing_end_time.json", replace(kValid, R"(, "end_time": 0.01)", ""), "solver.end_time",
                  {"is required", "a number in (0,"});
  expect_rejected("missing_water.json",
                  replace(kValid, R"("water": [{"lo": [0.1, 0.1], "hi": [0.3, 0.3]}],)", ""), "water",
                  {"is required", "non-empty array"});
}

TEST_F(SceneCli, WrongType) {
  expect_rejected("dx_string.json", replace(kValid, R"("dx": 0.02)", R"("dx": "0.02")"), "solver.dx",
                  {"must be a number", "a string"});
  expect_rejected(
      "lo_length.json",
      replace(kValid, R"("lo": [0.0, 0.0], "hi": [1.0, 0.5])", R"("lo": [0.0, 0.0, 0.0], "hi": [1.0, 0.5])"),
      "domain.lo", {"array of 2 numbers"});
  expect_rejected("hydrostatic_number.json",
                  replace(kValid, R"("hi": [0.3, 0.3]})", R"("hi": [0.3, 0.3], "hydrostatic": 1})"),
                  "water.0.hydrostatic", {"true or false"});
}

TEST_F(SceneCli, OutOfRangeNumbers) {
  expect_rejected("negative_dx.json", replace(kValid, R"("dx": 0.02)", R"("dx": -0.02)"), "solver.dx",
                  {"must be in (0, 0.125]", "-0.02"});
  expect_rejected("dimension_4.json", replace(kValid, R"("dimension": 2)", R"("dimension": 4)"), "dimension",
                  {"[2, 3]"});
  expect_rejected("psi_above_one.json", replace(kValid, R"("jbar_psi": 0.5)", R"("jbar_psi": 1.5)"),
                  "fluid.jbar_psi", {"[0, 1]", "1.5"});
  expect_rejected("empty_domain.json", replace(kValid, R"("hi": [1.0, 0.5])", R"("hi": [1.0, -0.5])"),
                  "domain.hi", {"must exceed domain.lo"});
}

TEST_F(SceneCli, PpcNotAPerfectPower) {
  expect_rejected("ppc5.json", replace(kValid, R"("ppc": 4)", R"("ppc": 5)"), "solver.ppc",
                  {"perfect square", "1, 4, 9"});
}

TEST_F(SceneCli, WaterOutsideTheDomain) {
  expect_rejected("water_outside.json", replace(kValid, R"("hi": [0.3, 0.3]})", R"("hi": [1.3, 0.3]})"),
                  "water.0.hi", {"inside the domain", "allows [0.04, 0.96]"});
}

TEST_F(SceneCli, UnknownChoices) {
  expect_rejected("cylinder.json", replace(kValid, R"("type": "half_space")", R"("type": "cylinder")"),
                  "boundaries.0.type", {"box|half_space", "cylinder"});
  expect_rejected("bad_condition.json", replace(kValid, R"("condition": "slip")", R"("condition": "glue")"),
                  "boundaries.0.condition", {"sticky|slip|separate"});
  expect_rejected("bad_precision.json", replace(kValid, R"("precision": "double")", R"("precision": "half")"),
                  "solver.precision", {"float|double"});
}

TEST_F(SceneCli, WaterOverlappingASolid) {
  // The floor plane raised to z = 0.2 cuts the water box [0.1, 0.3]^2.
  expect_rejected("overlap.json", replace(kValid, R"("point": [0.0, 0.1])", R"("point": [0.0, 0.2])"),
                  "water.0", {"overlaps solid boundary 'floor'", "free space"});
  // A box solid inside the water.
  expect_rejected(
      "overlap_box.json",
      replace(kValid, R"("boundaries": [)",
              R"("boundaries": [{"name": "column", "type": "box", "lo": [0.15, 0.0], "hi": [0.2, 0.4]},)"),
      "water.0", {"overlaps solid boundary 'column'"});
}

TEST_F(SceneCli, UnknownFieldListsTheKnownOnes) {
  // A misspelt setting must not silently fall back to its default; the message lists what is allowed,
  // including settings this scene left at their defaults (`max_dt`, `gravity`).
  expect_rejected("typo.json", replace(kValid, R"("cfl": 0.4)", R"("cfll": 0.4)"), "solver.cfll",
                  {"unknown field", "cfl", "max_dt", "gravity"});
  expect_rejected("typo_root.json", replace(kValid, R"("name": "valid",)", R"("nmae": "valid",)"), "nmae",
                  {"unknown field", "instruments"});
}

TEST_F(SceneCli, CrossReferences) {
  expect_rejected("bad_load.json", replace(kValid, R"("boundary": "floor")", R"("boundary": "gate")"),
                  "instruments.loads.0.boundary", {"names no boundary", "gate"});
  expect_rejected("gauge_outside.json", replace(kValid, R"("position": [0.2])", R"("position": [2.0])"),
                  "instruments.gauges.0.position", {"inside the domain", "[0, 1]"});
}

TEST_F(SceneCli, NotJsonAndMissingFile) {
  expect_rejected("broken.json", std::string(kValid).substr(0, 100), "", {"not valid JSON"});
  expect_rejected("notjson.json", "dimension = 2\n", "", {"not valid JSON"});
  expect_file_rejected((dir_ / "no_such_scene.json").string(), "", "", {"cannot open the scene file"});
}

TEST_F(SceneCli, BadOverridePaths) {
  const std::string file = write("valid.json", kValid);
  expect_file_rejected(file, " --set 'water.3.lo=[0,0]'", "water.3",
                       {"--set water.3.lo", "no such array element", "1 elements"});
  expect_file_rejected(file, " --set solver.dx.value=0.01", "solver.dx.value", {"not an object or array"});
  expect_file_rejected(file, " --set solver.ddx=0.01", "solver.ddx", {"unknown field", "dx"});
  // A value that is not JSON is a string, which a numeric field rejects.
  expect_file_rejected(file, " --set solver.dx=fine", "solver.dx", {"must be a number", "a string"});
}

// --set values: JSON where the text parses as JSON, a string otherwise; they change the scene.
TEST(SceneOverrides, ValuesParseAsJsonElseString) {
  const Scene base = parse_scene_text(kValid, "valid.json");
  EXPECT_EQ(base.solver.dx, 0.02);
  const Scene s = parse_scene_text(kValid, "valid.json",
                                   {{"solver.dx", "0.01"},                  // number
                                    {"solver.precision", "float"},          // not JSON: the string "float"
                                    {"solver.ppc", "9"},                    // integer
                                    {"water.0.hi", "[0.25, 0.35]"},         // array
                                    {"name", "my run"},                     // string with a space
                                    {"solver.gravity", "[0.0, -1.5]"},      // vector
                                    {"fluid", R"({"bulk_modulus": 1e5})"},  // a whole object replaced
                                    {"water.0.hydrostatic", "false"}});     // boolean
  EXPECT_EQ(s.solver.dx, 0.01);
  EXPECT_EQ(s.solver.precision, Precision::kFloat);
  EXPECT_EQ(s.solver.ppc, 9);
  EXPECT_EQ(s.water[0].hi[0], 0.25);
  EXPECT_EQ(s.water[0].hi[1], 0.35);
  EXPECT_EQ(s.name, "my run");
  EXPECT_EQ(s.solver.gravity[1], -1.5);
  EXPECT_EQ(s.fluid.bulk_modulus, 1e5);
  EXPECT_EQ(s.fluid.jbar_psi, 0.0);  // the replaced object no longer has it: the default
  EXPECT_FALSE(s.water[0].hydrostatic);
  // A quoted JSON string stays a string, even when it looks like a number.
  EXPECT_THROW(parse_scene_text(kValid, "valid.json", {{"solver.dx", "\"0.01\""}}), InputError);
  // A string field takes the quoted form as the bare word.
  EXPECT_EQ(parse_scene_text(kValid, "v.json", {{"name", "\"quoted\""}}).name, "quoted");
  // The last of two overrides of one path wins; a later override may reach into an earlier one's value.
  const Scene t = parse_scene_text(kValid, "v.json", {{"solver.cfl", "0.1"}, {"solver.cfl", "0.2"}});
  EXPECT_EQ(t.solver.cfl, 0.2);
  const Scene u = parse_scene_text(kValid, "v.json", {{"fluid", "{}"}, {"fluid.gamma", "3"}});
  EXPECT_EQ(u.fluid.gamma, 3.0);
  EXPECT_EQ(u.fluid.bulk_modulus, 2.0e7);  // the emptied object's default
  // path=value splits at the first '=': the value may contain '='.
  EXPECT_EQ(parse_override("name=a=b").value, "a=b");
  EXPECT_THROW(parse_override("solver.dx"), InputError);
}

TEST_F(SceneCli, OverridesReachTheRun) {
  const std::string file = write("valid.json", kValid);
  const CliResult c = flume("check " + file +
                            " --set solver.dx=0.01 --set solver.precision=float --set solver.end_time=0.25");
  ASSERT_EQ(c.rc, kExitOk) << c.err;
  EXPECT_NE(c.out.find("dx = 0.01 m"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("float"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("end_time = 0.25 s"), std::string::npos) << c.out;
  const CliResult b = flume("check " + file + " --set=solver.ppc=9");
  ASSERT_EQ(b.rc, kExitOk) << b.err;
  EXPECT_NE(b.out.find("ppc = 9"), std::string::npos) << b.out;
}

}  // namespace
}  // namespace flume

namespace flume {
namespace {

// Issue 29: hostile documents, `--set` paths and resolutions, refused alike by `check` and `run` (one
// validation function) with one line naming the file and the field, before anything is allocated.
TEST_F(SceneCli, HostileDocuments) {
  // 60,000 levels crashed `flume check` with SIGSEGV.
  expect_rejected("deep.json", std::string(60000, '[') + std::string(60000, ']'), "", {"nested deeper than 64"});
  expect_rejected("array.json", "[1, 2]", "", {"not an object"});
  expect_rejected("null.json", "null", "", {"not an object"});
  expect_rejected("overflow.json", replace(kValid, R"("dx": 0.02)", R"("dx": 1e999)"), "solver.dx",
                  {"out of range"});
  expect_file_rejected("/dev/zero", "", "", {"regular file"});
  // A 10 MB name, refused by the file's size; a 100 kB one by the string bound.
  expect_rejected("name10mb.json", replace(kValid, R"("name": "valid")", "\"name\": \"" + std::string(10 << 20, 'n') + "\""),
                  "", {"at most 4194304"});
  expect_rejected("name100kb.json", replace(kValid, R"("name": "valid")", "\"name\": \"" + std::string(100000, 'n') + "\""),
                  "name", {"100000 bytes", "at most 4096"});
  // 2,000 water boxes: under the document bounds, but the scene is stored whole in result.h5, which failed
  // to write it after the whole run.
  std::string boxes;
  for (int i = 0; i < 2000; ++i) boxes += std::string(i ? ", " : "") + R"({"lo": [0.1, 0.1], "hi": [0.3, 0.3]})";
  expect_rejected("boxes.json", replace(kValid, R"([{"lo": [0.1, 0.1], "hi": [0.3, 0.3]}])", "[" + boxes + "]"), "",
                  {"at most 60000"});
}

TEST_F(SceneCli, HostileOverridePaths) {
  const std::string file = write("valid.json", kValid);
  for (const std::string path : {"..", ".solver.dx", "solver.dx.", "solver..dx"}) {
    for (const std::string& cmd : std::vector<std::string>{"check ", "run --out " + (dir_ / "out").string() + " "}) {
      SCOPED_TRACE(cmd + path);
      const CliResult r = flume(cmd + file + " --set " + path + "=1");
      EXPECT_EQ(r.rc, kExitInvalidInput) << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      EXPECT_NE(r.err.find("--set: " + path + ": an empty segment"), std::string::npos) << r.err;
    }
  }
  // 1e999 ended as "internal error: number overflow", naming no file or field.
  expect_file_rejected(file, " --set solver.dx=1e999", "solver.dx", {"--set solver.dx", "out of range"});
}

TEST_F(SceneCli, ResolutionIsBoundedBeforeAllocating) {
  const std::string file = write("valid.json", kValid);
  // dx 1e-9 m passed `check`, and `run` allocated until memory ran out.
  expect_file_rejected(file, " --set solver.dx=1e-9", "solver.dx", {"cells across the domain", "at most 4e+06"});
  // 20 x 20 particles in the water box at dx 0.02 m, ppc 4; the bound is the scene's to raise.
  expect_file_rejected(file, " --set solver.max_particles=100", "solver.dx",
                       {"about 400 particles", "at most solver.max_particles = 100"});
  EXPECT_EQ(parse_scene_text(kValid, "v.json", {{"solver.max_particles", "400"}}).solver.max_particles, 400);
  // The Waseda basin at dx 1e9 m "completed" with 3 particles.
  expect_file_rejected(std::string(FLUME_SOURCE_DIR) + "/scenes/waseda/waseda_2d.json", " --set solver.dx=1e9",
                       "solver.dx", {"does not resolve water.0", "allowed: dx <="});
}

}  // namespace
}  // namespace flume
