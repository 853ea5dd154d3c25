// The command line as a new user meets it: --help on every command and subcommand of the registry (walked, not
// listed by hand), --version, and bad usage as one line with exit code 2 that points at --help.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/app.h"
#include "cli/registry.h"
#include "common/duration.h"
#include "common/errors.h"
#include "solver/progress.h"
#include "tests/common/run_command.h"

namespace fs = std::filesystem;
using flume::test::CommandResult;

namespace {

fs::path test_dir() {
  const fs::path d = fs::temp_directory_path() /
                     ("flume_test_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

CommandResult run_flume(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> argv = {FLUME_EXE};
  argv.insert(argv.end(), args.begin(), args.end());
  return flume::test::run_command(argv, dir, 60);
}

// Every command path of the tree: {"run"}, {"campaign"}, {"campaign", "run"}, ...
void walk(const CLI::App& app, std::vector<std::string> path, std::vector<std::vector<std::string>>& out) {
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    std::vector<std::string> p = path;
    p.push_back(sub->get_name());
    out.push_back(p);
    walk(*sub, p, out);
  }
}

std::string joined(const std::vector<std::string>& path) {
  std::string s;
  for (const auto& p : path) s += (s.empty() ? "" : " ") + p;
  return s;
}

}  // namespace

TEST(Cli, EveryCommandOfTheRegistryAnswersHelp) {
  const fs::path dir = test_dir();
  const auto app = flume::cli::build_app();
  std::vector<std::vector<std::string>> paths = {{}};
  walk(*app, {}, paths);
  // The registry's own list is in the tree, and the tree has the subcommands too.
  for (const auto& c : flume::cli::commands())
    EXPECT_NE(std::find(paths.begin(), paths.end(), std::vector<std::string>{c.name}), paths.end()) << c.name;
  EXPECT_GT(paths.size(), flume::cli::commands().size() + 1);
  for (const auto& path : paths) {
    SCOPED_TRACE("flume " + joined(path) + " --help");
    std::vector<std::string> args = path;
    args.push_back("--help");
    const CommandResult r = run_flume(args, dir);
    EXPECT_EQ(r.rc, flume::kExitOk) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    // The help names the command and says how to call it.
    if (!path.empty()) EXPECT_NE(r.out.find(path.back()), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("sage"), std::string::npos) << r.out;
  }
  fs::remove_all(dir);
}

TEST(Cli, VersionAndTopLevelHelp) {
  const fs::path dir = test_dir();
  const CommandResult v = run_flume({"--version"}, dir);
  EXPECT_EQ(v.rc, 0) << v.err;
  EXPECT_EQ(v.out.rfind("flume ", 0), 0u) << v.out;
  const CommandResult h = run_flume({"--help"}, dir);
  EXPECT_EQ(h.rc, 0);
  for (const auto& c : flume::cli::commands()) EXPECT_NE(h.out.find(c.name), std::string::npos) << c.name;
  fs::remove_all(dir);
}

// Bad usage: exit 2, one line on stderr naming what is wrong and pointing at the command's --help.
TEST(Cli, BadUsageIsOneLineWithExitTwoAndAHint) {
  const fs::path dir = test_dir();
  struct Bad {
    std::vector<std::string> args;
    std::string names, hint;
  };
  const std::vector<Bad> bad = {
      {{}, "needs a command", "flume --help"},
      {{"frobnicate"}, "frobnicate: unknown command", "flume --help"},
      {{"run", "scene.json"}, "--out: is required", "flume run --help"},
      {{"run", "scene.json", "--out", "o", "--colour"}, "--colour: unknown option", "flume run --help"},
      {{"run", "scene.json", "--out", "o", "--threads", "0"}, "--threads", "flume run --help"},
      {{"bench", "scene.json"}, "--steps: is required", "flume bench --help"},
      {{"check"}, "SCENE: is required", "flume check --help"},
      {{"campaign"}, "needs a command", "flume campaign --help"},
      {{"campaign", "rerun"}, "rerun: unknown command", "flume campaign --help"},
      {{"campaign", "export", "--db", "x.db"}, "--csv: is required", "flume campaign export --help"},
      {{"study", "tradeoff", "spec.json"}, "--db: is required", "flume study tradeoff --help"},
      {{"model", "test"}, "--out: is required", "flume model --help"},
      {{"calibrate", "spec.json", "--db", "x.db"}, "--out: is required", "flume calibrate --help"},
  };
  for (const auto& b : bad) {
    SCOPED_TRACE("flume " + joined(b.args));
    const CommandResult r = run_flume(b.args, dir);
    EXPECT_EQ(r.rc, flume::kExitInvalidInput) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(b.names), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(b.hint), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  fs::remove_all(dir);
}

// The progress line of `flume run`: speeds over the segment so far, the time left at that speed.
TEST(Cli, ProgressLineSaysWallTimeSpeedAndTimeLeft) {
  // 1 s of 4 simulated in 10 s of wall time, 100 steps of 1000 particles: 0.1 sim-s/wall-s, 1e4
  // particle-steps/s, 30 s left.
  const std::string line = flume::Progress::line(1.0, 4.0, 0.0, 100, 0, 0.01, 10.0, 1000);
  EXPECT_NE(line.find("t = 1.000 s / 4.000 s (25 %)"), std::string::npos) << line;
  EXPECT_NE(line.find("wall 0:10"), std::string::npos) << line;
  EXPECT_NE(line.find("0.1 sim-s/wall-s"), std::string::npos) << line;
  EXPECT_NE(line.find("1e+04 particle-steps/s"), std::string::npos) << line;
  EXPECT_NE(line.find("ETA 0:30"), std::string::npos) << line;
  // A resumed segment counts from where it started: 1 s more in 20 s, 3 s left at 0.05 sim-s/wall-s.
  const std::string resumed = flume::Progress::line(2.0, 5.0, 1.0, 300, 200, 0.01, 20.0, 1000);
  EXPECT_NE(resumed.find("ETA 1:00"), std::string::npos) << resumed;
  EXPECT_EQ(flume::hms(3725), "1:02:05");
  EXPECT_EQ(flume::hms(-1), "unknown");
}
