// Instability detection (issue 2, item 6): the Martin & Moyce dam break at CFL 5 (far past the explicit
// limit) run through `flume run` must end with exit code 3, status `unstable` and a message that says what
// went wrong, where and when; result.h5 must open and hold the records up to the failure.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "common/errors.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "store/h5/run_file.h"
#include "test_util.h"

namespace flume {
namespace {

namespace fs = std::filesystem;

const std::string kScene = std::string(FLUME_SOURCE_DIR) + "/scenes/dam_break/martin_moyce_2d.json";

class Unstable : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("flume_test_stability_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// Runs the scene at `cfl` through the CLI and checks the unstable-run contract; `min_records` is how many
// diagnostics records (200 Hz, plus the forced one at the failing step) the file must hold at least.
void check_unstable_run(const fs::path& dir, const std::string& cfl, size_t min_records) {
  const fs::path out = dir / ("run_cfl" + cfl);
  const std::string err = (dir / "stderr.txt").string();
  const int rc = test::run_command(std::string(FLUME_EXE) + " run " + kScene + " --out " + out.string() +
                                   " --set solver.cfl=" + cfl + " --quiet 2>" + err);
  const std::string stderr_text = test::read_text(err);
  ASSERT_EQ(rc, kExitUnstable) << stderr_text;
  EXPECT_NE(stderr_text.find("unstable"), std::string::npos) << stderr_text;

  // run.json: status and a message with what, when (time and step) and where (a position).
  ASSERT_TRUE(fs::exists(out / "run.json"));
  const auto run = nlohmann::json::parse(test::read_text((out / "run.json").string()));
  EXPECT_EQ(run.at("status"), "unstable");
  const std::string msg = run.at("message").get<std::string>();
  std::smatch m;
  const std::regex when(R"(at t = ([0-9.eE+-]+) s \(step ([0-9]+))");
  ASSERT_TRUE(std::regex_search(msg, m, when)) << "no time and step in: " << msg;
  const double t_fail = std::stod(m[1]);
  const long step_fail = std::stol(m[2]);
  EXPECT_TRUE(std::regex_search(msg, std::regex(R"(at \(-?[0-9.eE+-]+, -?[0-9.eE+-]+\) m)")))
      << "no position in: " << msg;
  EXPECT_TRUE(msg.find("NaN") != std::string::npos || msg.find("left the domain") != std::string::npos ||
              msg.find("energy grew") != std::string::npos)
      << "no cause in: " << msg;
  EXPECT_NE(msg.find("solver.cfl"), std::string::npos) << "no remedy in: " << msg;
  EXPECT_EQ(run.at("cost").at("steps").get<long>(), step_fail);
  EXPECT_GT(run.at("cost").at("particles").get<long>(), 0);
  std::printf("[ info ] cfl %s: unstable at step %ld, t = %.4g s: %s\n", cfl.c_str(), step_fail, t_fail,
              msg.c_str());

  // The instability was caught where it happened: the run stopped early, not at its end time.
  const Scene scene = load_scene(kScene);
  EXPECT_LT(t_fail, 0.5 * scene.solver.end_time);

  // result.h5 is complete (renamed from .part), opens, and holds the records up to the failure.
  ASSERT_TRUE(fs::exists(out / "result.h5"));
  EXPECT_FALSE(fs::exists(out / "result.h5.part"));
  h5::Reader r((out / "result.h5").string());
  EXPECT_EQ(r.string_attribute("/", "status"), "unstable");
  EXPECT_EQ(r.string_attribute("/", "message"), msg);
  const auto time = r.read_vector("/diagnostics/time");
  const auto step = r.read_vector("/diagnostics/step");
  const auto mass = r.read_vector("/diagnostics/mass");
  const auto total = r.read_vector("/diagnostics/total");
  ASSERT_GE(time.size(), min_records);
  ASSERT_EQ(step.size(), time.size());
  EXPECT_EQ(time.front(), 0.0);
  for (size_t i = 1; i < time.size(); ++i) EXPECT_GT(time[i], time[i - 1]);
  // The last diagnostics record is the failing step itself (forced), the ones before it are the steps
  // before, sampled at the scene's 200 Hz, and were finite.
  EXPECT_NEAR(time.back(), t_fail, 1e-6 * t_fail + 1e-12);
  EXPECT_EQ(static_cast<long>(step.back()), step_fail);
  for (size_t i = 0; i + 1 < time.size(); ++i) {
    EXPECT_TRUE(std::isfinite(total[i])) << "record " << i;
    EXPECT_EQ(mass[i], mass[0]);
  }
  const auto gauge_t = r.read_vector("/gauges/back/time");
  const auto gauge_h = r.read_vector("/gauges/back/elevation");
  ASSERT_GE(gauge_t.size(), 1u);
  EXPECT_EQ(gauge_t.size(), gauge_h.size());
  EXPECT_NEAR(gauge_h.front(), 0.1143, 0.01);  // the column's initial height at the back wall
  EXPECT_GE(r.list("/snapshots").size(), 1u);  // the t = 0 snapshot
}

// CFL 5, the issue's case: the energy audit stops it at its first step.
TEST_F(Unstable, Cfl5EndsUnstableWithReadableMessageAndValidOutput) { check_unstable_run(dir_, "5", 2); }

// CFL 0.9 is past the limit too, but grows slowly: the file holds the regular records before the failure.
TEST_F(Unstable, Cfl09FailsLaterAndKeepsTheRecordsBefore) { check_unstable_run(dir_, "0.9", 3); }

// The same scene at its own CFL is stable: the failure above is the time step's, not the scene's.
TEST(Stable, ShippedCflRunsWithoutFlag) {
  const Scene scene =
      load_scene(kScene, {{"solver.end_time", "0.02"}, {"instruments.snapshot_rate_hz", "0"}});
  auto sim = make_simulation(scene, {});
  EXPECT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kOk) << sim->message();
}

// In process: the step that fails reports kUnstable, and stepping again does nothing.
TEST(UnstableInProcess, StepAfterFailureIsANoOp) {
  const Scene scene = load_scene(kScene, {{"solver.cfl", "5"}, {"instruments.snapshot_rate_hz", "0"}});
  auto sim = make_simulation(scene, {});
  ASSERT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kUnstable);
  EXPECT_FALSE(sim->message().empty());
  const double t = sim->time();
  const long n = sim->steps();
  EXPECT_EQ(sim->step(), RunStatus::kUnstable);
  EXPECT_EQ(sim->time(), t);
  EXPECT_EQ(sim->steps(), n);
}

}  // namespace
}  // namespace flume
