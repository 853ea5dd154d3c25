// Issue 29: a `flume run` killed part-way keeps what it computed. SIGTERM and SIGINT stop it cleanly (result.h5
// and run.json say "killed", exit 128 + signal); SIGKILL leaves result.h5.part, which opens in HDF5 and holds
// the record up to the last flush. Each run is the Martin & Moyce column with a long end time, flushed every
// 0.2 s and signalled once a flush after t = 0 is on disk; it would take minutes to finish.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "store/h5/run_file.h"
#include "tests/common/run_command.h"

namespace {

namespace fs = std::filesystem;

struct Flushed {
  double t = 0;       // the file's flushed_at_s
  size_t samples = 0;  // rows of /diagnostics/time
};

// What result.h5.part holds, when it opens; t = 0 when it does not (yet).
Flushed read_part(const fs::path& file) {
  Flushed f;
  try {
    flume::h5::Reader r(file.string());
    f.t = r.number_attribute("/", "flushed_at_s");
    f.samples = r.read_vector("/diagnostics/time").size();
  } catch (const std::exception&) {
    f = {};
  }
  return f;
}

void kill_after_first_flush(int sig) {
  // The running solver holds HDF5's lock on its file; this process reads it without taking one.
  setenv("HDF5_USE_FILE_LOCKING", "FALSE", 1);
  const fs::path dir = fs::temp_directory_path() / ("flume_killed_" + std::to_string(getpid()) + "_" + std::to_string(sig));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path out = dir / "run";
  const pid_t pid = flume::test::spawn(
      {FLUME_EXE, "run", std::string(FLUME_SOURCE_DIR) + "/scenes/dam_break/martin_moyce_2d.json", "--out",
       out.string(), "--threads", "1", "--quiet", "--flush-every", "0.2", "--set", "solver.end_time=60", "--set",
       "instruments.snapshot_rate_hz=0"},
      dir / "stdout.log", dir / "stderr.log");
  ASSERT_GT(pid, 0);
  Flushed seen;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  // Wait for a flush that holds at least two diagnostics samples: on a slow build (sanitizers) the first
  // flush may come before the run has simulated past its first sample.
  while ((seen.t <= 0 || seen.samples < 2) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, WNOHANG), 0)
        << "the run ended before its first flush: " << flume::test::read_file(dir / "stderr.log");
    seen = read_part(out / "result.h5.part");
  }
  ASSERT_GT(seen.t, 0) << "no flush after t = 0 within 60 s";
  ASSERT_GE(seen.samples, 2u) << "no flush with two diagnostics samples within 60 s";
  kill(pid, sig);
  const int rc = flume::test::wait_for(pid, 60);
  EXPECT_EQ(rc, 128 + sig) << flume::test::read_file(dir / "stderr.log");

  const fs::path result = out / (sig == SIGKILL ? "result.h5.part" : "result.h5");
  ASSERT_TRUE(fs::exists(result)) << result;
  flume::h5::Reader r(result.string());  // throws, failing the test, when HDF5 cannot open it
  const auto time = r.read_vector("/diagnostics/time");
  EXPECT_GE(time.size(), seen.samples);
  EXPECT_GT(time.size(), 1u);
  EXPECT_EQ(r.read_vector("/diagnostics/mass").size(), time.size());
  EXPECT_EQ(r.read_vector("/gauges/back/time").size(), r.read_vector("/gauges/back/elevation").size());
  EXPECT_GE(r.number_attribute("/", "flushed_at_s"), seen.t);
  if (sig == SIGKILL) {
    EXPECT_FALSE(fs::exists(out / "result.h5")) << "a run killed outright must not look finished";
    EXPECT_FALSE(fs::exists(out / "run.json"));
    EXPECT_EQ(r.string_attribute("/", "status"), "running");
  } else {
    EXPECT_EQ(r.string_attribute("/", "status"), "killed");
    const auto run = nlohmann::json::parse(flume::test::read_file(out / "run.json"));
    EXPECT_EQ(run.at("status"), "killed");
    EXPECT_NE(run.at("message").get<std::string>().find("killed by signal " + std::to_string(sig)), std::string::npos);
    EXPECT_GT(run.at("cost").at("steps").get<long>(), 0);
    EXPECT_FALSE(fs::exists(out / "result.h5.part"));
  }
  fs::remove_all(dir);
}

}  // namespace

TEST(KilledRun, SigtermStopsCleanlyWithTheRecordAndRunJsonSayingKilled) { kill_after_first_flush(SIGTERM); }
TEST(KilledRun, SigintStopsCleanlyWithTheRecordAndRunJsonSayingKilled) { kill_after_first_flush(SIGINT); }
TEST(KilledRun, SigkillLeavesAPartFileThatOpensWithTheRecordToTheLastFlush) { kill_after_first_flush(SIGKILL); }
