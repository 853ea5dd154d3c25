// `flume calibrate` end to end on the `gauge` test stand-in: twin experiments (a record simulated at known
// parameters, with noise, is the target; the calibration must find the parameters again), multi-start with a
// global algorithm, kill -9 and resume, and malformed inputs. Each test runs the real executable.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "store/h5/run_file.h"
#include "tests/common/run_command.h"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

fs::path test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::temp_directory_path() / ("flume_calibrate_" + std::to_string(getpid()) + "_" +
                                                    info->test_suite_name() + "_" + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write_file(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

using flume::test::read_file;
using flume::test::spawn;
using flume::test::wait_for;
using Result = flume::test::CommandResult;

// timeout_s only guards against a hung child (it is not a speed check): the slowest of these, the three-start
// global calibration, takes 45-56 s alone on the 2-core VM and passed 140 s on a machine loaded with a 2-thread
// solver run beside ctest -j2 (2026-12-03), so the guard is set well clear of that.
Result run(const std::vector<std::string>& args, const fs::path& dir, double timeout_s = 600) {
  return flume::test::run_command(args, dir, timeout_s);
}

std::vector<std::string> flume_cmd(std::initializer_list<std::string> args) {
  std::vector<std::string> v = {FLUME_EXE};
  v.insert(v.end(), args);
  return v;
}

using Rows = std::vector<std::vector<std::string>>;
Rows query(const fs::path& db, const std::string& sql) {
  sqlite3* h = nullptr;
  Rows rows;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(h);
    return rows;
  }
  sqlite3_busy_timeout(h, 10000);
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v2(h, sql.c_str(), -1, &s, nullptr) == SQLITE_OK) {
    while (sqlite3_step(s) == SQLITE_ROW) {
      std::vector<std::string> row;
      for (int i = 0; i < sqlite3_column_count(s); ++i) {
        const unsigned char* t = sqlite3_column_text(s, i);
        row.push_back(t ? reinterpret_cast<const char*>(t) : "NULL");
      }
      rows.push_back(row);
    }
  }
  sqlite3_finalize(s);
  sqlite3_close(h);
  return rows;
}
std::string scalar(const fs::path& db, const std::string& sql) {
  const Rows r = query(db, sql);
  return r.empty() || r[0].empty() ? "" : r[0][0];
}

constexpr double kNoise_m = 0.002;  // issue 6: 2 mm of noise on the twin's target
constexpr double kT99 = 0.8, kGate = 0.085;

// The twin's target: WG1 of the stand-in at the true parameters plus Gaussian noise, written by
// `flume calibrate target`. Returns the RMS of the noise actually added over [t0, t1], measured here against
// the noise-free record: the misfit the true parameters score, which a converged calibration cannot exceed.
double make_target(const fs::path& dir, const std::vector<std::string>& sets, double t0, double t1,
                   std::uint64_t seed = 7, double time_offset_s = 0.0) {
  std::vector<std::string> args = flume_cmd({"model", "gauge", "--out", (dir / "truth").string()});
  for (const auto& s : sets) args.insert(args.end(), {"--set", s});
  EXPECT_EQ(run(args, dir).rc, 0);
  const std::string h5 = (dir / "truth" / "result.h5").string();
  const Result r =
      run(flume_cmd({"calibrate", "target", h5, "--out", (dir / "raw.csv").string(), "--gauge", "WG1",
                     "--noise-m", std::to_string(kNoise_m), "--seed", std::to_string(seed)}),
          dir);
  EXPECT_EQ(r.rc, 0) << r.err;
  const auto time = flume::h5::read_vector(h5, "/gauges/WG1/time");
  const auto eta = flume::h5::read_vector(h5, "/gauges/WG1/elevation");
  std::ifstream in(dir / "raw.csv");
  std::ofstream out(dir / "target.csv");
  std::string line;
  std::getline(in, line);
  out << line << "\n";
  out.precision(17);
  double sum2 = 0;
  int n = 0;
  for (size_t k = 0; std::getline(in, line); ++k) {
    const auto comma = line.find(',');
    const double t = std::stod(line.substr(0, comma)), v = std::stod(line.substr(comma + 1));
    EXPECT_NEAR(t, time[k], 1e-12);
    out << t + time_offset_s << "," << v << "\n";
    if (t + time_offset_s >= t0 - 1e-9 && t + time_offset_s <= t1 + 1e-9) {
      sum2 += (v - eta[k]) * (v - eta[k]);
      ++n;
    }
  }
  return std::sqrt(sum2 / n);
}

json load_json(const fs::path& p) { return json::parse(read_file(p)); }

double best(const json& j, const std::string& path) {
  return j.at("best").at("parameters").at(path).get<double>();
}

const char* kT99Path = "reservoir.forcing.t99_s";
const char* kGatePath = "reservoir.gate_height_m";

std::string two_parameter_spec(const std::string& name, const std::string& algorithm,
                               const std::string& extra,
                               const std::string& objective = R"({"window": [0, 5]})") {
  return R"({"name": ")" + name + R"(", "model": "gauge",
  "overrides": {"reservoir.forcing.model": "exponential"},
  "targets": [{"file": "target.csv"}],
  "parameters": [{"path": "reservoir.forcing.t99_s", "lower": 0.05, "upper": 2.0, "start": 0.2},
                 {"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.12}],
  "objective": )" +
         objective + R"(,
  "algorithm": )" +
         algorithm + extra + "}";
}

// The 95 % interval of a parameter in `flume surrogate posterior`'s table (parameter,best,mean,median,lo,hi).
std::pair<double, double> posterior_interval(const std::string& out, const std::string& path) {
  const auto at = out.find("\n" + path + ",");
  if (at == std::string::npos) {
    ADD_FAILURE() << "no row for " << path << " in\n" << out;
    return {NAN, NAN};
  }
  std::istringstream row(out.substr(at + path.size() + 2));
  double best, mean, median, lo, hi;
  char comma;
  row >> best >> comma >> mean >> comma >> median >> comma >> lo >> comma >> hi;
  return {lo, hi};
}

}  // namespace

// Issue 6 point 1 on the stand-in: BOBYQA from t99 = 0.2 s, gate 0.12 m recovers t99 = 0.8 s and gate
// 0.085 m within 10 % in at most 80 evaluations, with an RMS misfit no larger than the noise.
TEST(CalibrateTwin, BobyqaRecoversTwoParametersFromADistantStart) {
  const fs::path dir = test_dir();
  const double noise_rms =
      make_target(dir, {"reservoir.forcing.t99_s=0.8", "reservoir.gate_height_m=0.085"}, 0, 5);
  write_file(dir / "spec.json", two_parameter_spec("twin", R"({"name": "BOBYQA", "max_evaluations": 80})",
                                                   R"(, "profile": {"points": 4, "span": 0.1})"));
  const fs::path db = dir / "study.db", out = dir / "out";
  const Result r = run(flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", db.string(), "--out",
                                  out.string(), "--workers", "2"}),
                       dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const json j = load_json(out / "calibration.json");
  EXPECT_EQ(j["status"], "finished");
  EXPECT_NEAR(best(j, kT99Path), kT99, 0.1 * kT99);
  EXPECT_NEAR(best(j, kGatePath), kGate, 0.1 * kGate);
  EXPECT_LE(j["starts"][0]["evaluations"].get<int>(), 80);
  const double rms = j["best"]["terms"]["rms_m"].get<double>();
  EXPECT_LE(rms, noise_rms) << "the true parameters score " << noise_rms << " m";
  EXPECT_GT(rms, 0.9 * noise_rms) << "a fit far below the noise is fitting the noise";

  // Profiles: each has its minimum at the optimum and rises on both sides (the parameters are identifiable).
  for (const char* path : {kT99Path, kGatePath}) {
    const auto& p = j["profiles"][path];
    const auto& f = p["objective"];
    ASSERT_EQ(f.size(), 9u) << path;
    for (size_t k = 0; k < f.size(); ++k)
      EXPECT_GE(f[k].get<double>(), f[4].get<double>()) << path << " point " << k;
    EXPECT_GT(p["rise_low"].get<double>(), 0.05) << path;
    EXPECT_GT(p["rise_high"].get<double>(), 0.05) << path;
  }
  ASSERT_TRUE(j["identifiability"]["available"].get<bool>());
  EXPECT_LT(std::fabs(j["identifiability"]["correlation"][0][1].get<double>()), 0.95);
  // The true values lie within a few standard errors (independent-residual errors are optimistic: 5 of them).
  EXPECT_LT(std::fabs(best(j, kT99Path) - kT99),
            5 * j["identifiability"]["std_error"][kT99Path].get<double>());

  // Every evaluation is in the store, keyed by its run; runs are no more than distinct points.
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM evaluations WHERE phase = 'optimize'"),
            std::to_string(j["starts"][0]["evaluations"].get<int>()));
  EXPECT_EQ(
      scalar(db, "SELECT count(*) FROM evaluations e LEFT JOIN runs r ON r.id = e.run WHERE r.id IS NULL"),
      "0");
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs WHERE status = 'ok'"),
            scalar(db, "SELECT count(*) FROM runs"));
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs"),
            std::to_string(j["evaluations"]["runs_in_store"].get<int>()));
  for (const char* f : {"fit.svg", "profiles.svg", "history.svg", "fit.csv"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  const std::string svg = read_file(out / "fit.svg");
  EXPECT_NE(svg.find("fitted"), std::string::npos);
  EXPECT_NE(svg.find("target"), std::string::npos);
  const Result h = run(flume_cmd({"calibrate", "history", "--db", db.string(), "--name", "twin"}), dir);
  ASSERT_EQ(h.rc, 0) << h.err;
  EXPECT_NE(h.out.find("twin,optimize,0,0,"), std::string::npos);

  // Issue 27 item 4 on the stand-in: the posterior on the series emulator (the runs' records read back, their
  // residuals the calibration's: the command checks each run's RMS against the stored one) holds the truth.
  const Result p = run(flume_cmd({"surrogate", "posterior", "--db", db.string(), "--calibration", "twin",
                                  "--noise-m", std::to_string(kNoise_m)}),
                       dir);
  ASSERT_EQ(p.rc, 0) << p.err;
  std::printf("%s", p.out.c_str());
  EXPECT_NE(p.out.find("series emulator"), std::string::npos) << p.out;
  for (const auto& [path, truth] : {std::pair{kT99Path, kT99}, std::pair{kGatePath, kGate}}) {
    const auto [lo, hi] = posterior_interval(p.out, path);
    EXPECT_LE(lo, truth) << path;
    EXPECT_GE(hi, truth) << path;
  }
}

// Issue 27 item 4: a calibration stopped after 12 optimizer evaluations leaves the truth between its path and
// its profile steps, where the series emulator extrapolates and the posterior misses it. The refinement runs
// posterior draws as evaluations, round after round, and the posterior then holds the truth; the same command
// again replays the rounds from the store and runs nothing.
TEST(CalibrateTwin, PosteriorRefinementRunsDrawsUntilTheEmulatorKnowsThePosteriorsRegion) {
  const fs::path dir = test_dir();
  make_target(dir, {"reservoir.forcing.t99_s=0.8", "reservoir.gate_height_m=0.085"}, 0, 5);
  write_file(dir / "spec.json",
             two_parameter_spec("short", R"({"name": "BOBYQA", "max_evaluations": 12})", ""));
  const fs::path db = dir / "study.db";
  ASSERT_EQ(run(flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", db.string(), "--out",
                           (dir / "out").string(), "--workers", "2"}),
                dir)
                .rc,
            0);
  auto holds = [](const std::string& out) {
    bool all = true;
    for (const auto& [path, truth] : {std::pair{kT99Path, kT99}, std::pair{kGatePath, kGate}}) {
      const auto [lo, hi] = posterior_interval(out, path);
      all = all && lo <= truth && truth <= hi;
    }
    return all;
  };
  const std::vector<std::string> plain =
      flume_cmd({"surrogate", "posterior", "--db", db.string(), "--calibration", "short", "--noise-m",
                 std::to_string(kNoise_m)});
  const Result p0 = run(plain, dir);
  ASSERT_EQ(p0.rc, 0) << p0.err;
  EXPECT_FALSE(holds(p0.out)) << "the case no longer needs refinement:\n" << p0.out;
  // The best of the 32 scores 1.5 sigma, beyond what noise alone gives over 501 residuals (1.1 sigma):
  // warned.
  EXPECT_NE(p0.out.find("the residual is not the noise alone"), std::string::npos) << p0.out;

  std::vector<std::string> refined = plain;
  refined.insert(refined.end(), {"--refine", "8", "--rounds", "2", "--workers", "2"});
  const Result p1 = run(refined, dir);
  ASSERT_EQ(p1.rc, 0) << p1.err;
  std::printf("%s", p1.out.c_str());
  EXPECT_TRUE(holds(p1.out)) << p1.out;
  EXPECT_EQ(p1.out.find("the residual is not the noise alone"), std::string::npos) << p1.out;
  EXPECT_NE(p1.out.find("# refine round 2"), std::string::npos) << p1.out;
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM evaluations WHERE phase = 'refine' AND start = 1"), "8");
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM evaluations WHERE phase = 'refine' AND start = 2"), "8");

  const std::string runs = scalar(db, "SELECT count(*) FROM runs");
  const Result p2 = run(refined, dir);
  ASSERT_EQ(p2.rc, 0) << p2.err;
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs"), runs) << "a replayed round ran its draws again";
  EXPECT_EQ(p2.out, p1.out);
}

// Window continuation (objective.stages): trailing undulations whose period follows the front's height give
// the misfit over 0-5 s a local minimum every period (cycle skipping), and BOBYQA over the whole window stops
// in one far from the truth, scoring many times the noise. Fitting 0-1.5 s first (the front and a few
// undulations, whose phase has not yet drifted a period) and then the window from there recovers the truth,
// scores the noise, and leaves a store the posterior holds the truth with.
TEST(CalibrateTwin, WindowContinuationReachesTheBasinThatCycleSkippingHidesFromOneWindow) {
  const fs::path dir = test_dir();
  const double noise_rms = make_target(
      dir, {"reservoir.forcing.t99_s=0.8", "reservoir.gate_height_m=0.085", "undulation_m=0.04"}, 0, 5);
  auto spec = [](const std::string& name, const std::string& stages) {
    return R"({"name": ")" + name + R"(", "model": "gauge",
      "overrides": {"reservoir.forcing.model": "exponential", "undulation_m": 0.04},
      "targets": [{"file": "target.csv"}],
      "parameters": [{"path": "reservoir.forcing.t99_s", "lower": 0.05, "upper": 2.0, "start": 0.2},
                     {"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.12}],
      "objective": {"window": [0, 5])" +
           stages + R"(},
      "algorithm": {"name": "BOBYQA", "max_evaluations": 80}, "profile": {"points": 1, "span": 0.01}})";
  };
  write_file(dir / "plain.json", spec("plain", ""));
  write_file(dir / "staged.json", spec("staged", R"(, "stages": [1.5])"));
  const fs::path db = dir / "study.db";
  for (const char* name : {"plain", "staged"}) {
    const Result r = run(flume_cmd({"calibrate", (dir / (std::string(name) + ".json")).string(), "--db",
                                    db.string(), "--out", (dir / name).string(), "--workers", "2"}),
                         dir);
    ASSERT_EQ(r.rc, 0) << name << ": " << r.err;
  }
  const json plain = load_json(dir / "plain" / "calibration.json");
  const json staged = load_json(dir / "staged" / "calibration.json");
  EXPECT_GT(plain["best"]["terms"]["rms_m"].get<double>(), 3 * noise_rms)
      << "the case shows nothing unless one window's optimizer stops in a local minimum";
  EXPECT_NEAR(best(staged, kT99Path), kT99, 0.02 * kT99);
  EXPECT_NEAR(best(staged, kGatePath), kGate, 0.01 * kGate);
  EXPECT_LE(staged["best"]["terms"]["rms_m"].get<double>(), noise_rms);
  EXPECT_GT(staged["starts"][0]["stage_evaluations"].get<int>(), 0);
  EXPECT_EQ(staged["objective"]["stages_end_s"], json::array({1.5}));

  // The stage's evaluations are stored with the whole window's terms (what the posterior reads) and the
  // stage's own objective beside them.
  const std::string staged_id = scalar(db, "SELECT id FROM campaigns WHERE name = 'staged'");
  EXPECT_EQ(
      scalar(db, "SELECT count(*) FROM evaluations WHERE phase = 'stage-1' AND campaign = " + staged_id),
      std::to_string(staged["starts"][0]["stage_evaluations"].get<int>()));
  const json stage_terms = json::parse(
      scalar(db, "SELECT terms FROM evaluations WHERE phase = 'stage-1' AND campaign = " + staged_id +
                     " ORDER BY seq LIMIT 1"));
  EXPECT_EQ(stage_terms["stage"]["window_s"], json::array({0.0, 1.5}));
  EXPECT_EQ(stage_terms["gauges"]["WG1"]["samples"].get<int>(), 501) << "the whole window's terms";
  EXPECT_TRUE(stage_terms["stage"]["objective"].is_number());

  const Result p = run(flume_cmd({"surrogate", "posterior", "--db", db.string(), "--calibration", "staged",
                                  "--noise-m", std::to_string(kNoise_m)}),
                       dir);
  ASSERT_EQ(p.rc, 0) << p.err;
  for (const auto& [path, truth] : {std::pair{kT99Path, kT99}, std::pair{kGatePath, kGate}}) {
    const auto [lo, hi] = posterior_interval(p.out, path);
    EXPECT_LE(lo, truth) << path << "\n" << p.out;
    EXPECT_GE(hi, truth) << path << "\n" << p.out;
  }
}

// Issue 6 point 1: the global algorithm (CRS2_LM, polished by BOBYQA) from three starts finds the same
// optimum.
TEST(CalibrateTwin, GlobalAlgorithmFromThreeStartsFindsTheSameOptimum) {
  const fs::path dir = test_dir();
  const double noise_rms =
      make_target(dir, {"reservoir.forcing.t99_s=0.8", "reservoir.gate_height_m=0.085"}, 0, 5);
  write_file(
      dir / "spec.json",
      two_parameter_spec(
          "global",
          R"({"name": "CRS2_LM", "max_evaluations": 50, "polish": "BOBYQA", "polish_evaluations": 30, "seed": 3})",
          R"(, "starts": [{"reservoir.forcing.t99_s": 1.8, "reservoir.gate_height_m": 0.05},
                                {"reservoir.forcing.t99_s": 0.1, "reservoir.gate_height_m": 0.15}],
                     "profile": {"points": 0})"));
  const fs::path out = dir / "out";
  const Result r = run(flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", (dir / "s.db").string(),
                                  "--out", out.string(), "--workers", "2"}),
                       dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const json j = load_json(out / "calibration.json");
  ASSERT_EQ(j["starts"].size(), 3u);
  for (const auto& s : j["starts"]) {
    EXPECT_TRUE(s["same_optimum"].get<bool>()) << s.dump();
    EXPECT_NEAR(s["to"][kT99Path].get<double>(), kT99, 0.1 * kT99) << s.dump();
    EXPECT_NEAR(s["to"][kGatePath].get<double>(), kGate, 0.1 * kGate) << s.dump();
    EXPECT_LE(s["objective"].get<double>(), noise_rms) << s.dump();
  }
  // The three optima agree to 1 % of each parameter's value.
  for (const auto& s : j["starts"]) {
    EXPECT_NEAR(s["to"][kT99Path].get<double>(), best(j, kT99Path), 0.01 * best(j, kT99Path));
    EXPECT_NEAR(s["to"][kGatePath].get<double>(), best(j, kGatePath), 0.01 * best(j, kGatePath));
  }
}

// Issue 6 point 2 on the stand-in: the table forcing's five hold fractions, all free from 0.5, are recovered
// within 0.1 everywhere along the curve.
TEST(CalibrateTwin, TableForcingRecoversTheHoldCurve) {
  const fs::path dir = test_dir();
  const std::vector<std::array<double, 2>> truth = {{0, 1}, {0.3, 0.75}, {0.6, 0.4}, {0.9, 0.15}, {1.2, 0}};
  const double noise_rms =
      make_target(dir,
                  {"reservoir.forcing.model=table",
                   "reservoir.forcing.table=[[0,1],[0.3,0.75],[0.6,0.4],[0.9,0.15],[1.2,0]]",
                   "reservoir.gate_height_m=0.085"},
                  0, 5, 11);
  std::string params;
  for (int i = 0; i < 5; ++i)
    params += std::string(i ? "," : "") + R"({"path": "reservoir.forcing.table.)" + std::to_string(i) +
              R"(.1", "lower": 0, "upper": 1, "start": 0.5})";
  write_file(dir / "spec.json", R"({"name": "table", "model": "gauge",
  "overrides": {"reservoir.forcing.model": "table", "reservoir.gate_height_m": 0.085,
                "reservoir.forcing.table": [[0, 0.5], [0.3, 0.5], [0.6, 0.5], [0.9, 0.5], [1.2, 0.5]]},
  "targets": [{"file": "target.csv", "gauges": {"WG1": "WG1 [m]"}}],
  "parameters": [)" + params + R"(],
  "objective": {"window": [0, 5]},
  "algorithm": {"name": "BOBYQA", "max_evaluations": 200},
  "profile": {"points": 0}})");
  const fs::path out = dir / "out";
  const Result r = run(flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", (dir / "s.db").string(),
                                  "--out", out.string(), "--workers", "2"}),
                       dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const json j = load_json(out / "calibration.json");
  EXPECT_LE(j["best"]["terms"]["rms_m"].get<double>(), noise_rms);
  auto hold = [](const std::vector<std::array<double, 2>>& tab, double t) {
    if (t >= tab.back()[0]) return tab.back()[1];
    size_t k = 1;
    while (tab[k][0] < t) ++k;
    return tab[k - 1][1] + (t - tab[k - 1][0]) / (tab[k][0] - tab[k - 1][0]) * (tab[k][1] - tab[k - 1][1]);
  };
  auto fitted = truth;
  for (int i = 0; i < 5; ++i) fitted[i][1] = best(j, "reservoir.forcing.table." + std::to_string(i) + ".1");
  double worst = 0;
  for (double t = 0; t <= 1.5; t += 0.001)
    worst = std::max(worst, std::fabs(hold(fitted, t) - hold(truth, t)));
  EXPECT_LE(worst, 0.1) << j["best"].dump();
}

// Issue 6 point 3: killed with SIGKILL mid-calibration, the rerun continues from the stored evaluations: no
// finished run is run again, and it ends where an uninterrupted calibration ends, evaluation for evaluation.
TEST(CalibrateResume, KillNineThenRerunRepeatsNoRunAndEndsAtTheSameOptimum) {
  const fs::path dir = test_dir();
  make_target(dir, {"reservoir.forcing.t99_s=0.8", "reservoir.gate_height_m=0.085"}, 0, 5);
  write_file(dir / "spec.json", two_parameter_spec("resume", R"({"name": "BOBYQA", "max_evaluations": 40})",
                                                   R"(, "profile": {"points": 1, "span": 0.05})"));
  const std::string spec = (dir / "spec.json").string();

  const fs::path ref_db = dir / "ref.db";
  const Result ref =
      run(flume_cmd({"calibrate", spec, "--db", ref_db.string(), "--out", (dir / "ref").string()}), dir);
  ASSERT_EQ(ref.rc, 0) << ref.err;

  const fs::path db = dir / "killed.db";
  const pid_t pid =
      spawn(flume_cmd({"calibrate", spec, "--db", db.string(), "--out", (dir / "killed").string()}),
            dir / "k.out", dir / "k.err");
  ASSERT_GT(pid, 0);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (!fs::exists(db)) continue;
    const std::string ok = scalar(db, "SELECT count(*) FROM runs WHERE status = 'ok'");
    if (!ok.empty() && std::stoi(ok) >= 12) break;
  }
  kill(pid, SIGKILL);
  ASSERT_EQ(wait_for(pid, 30), 128 + SIGKILL);
  const Rows finished_before = query(db, "SELECT id, finished FROM runs WHERE status = 'ok'");
  ASSERT_GE(finished_before.size(), 12u);
  ASSERT_FALSE(fs::exists(dir / "killed" / "calibration.json"));

  const Result again =
      run(flume_cmd({"calibrate", spec, "--db", db.string(), "--out", (dir / "killed").string()}), dir);
  ASSERT_EQ(again.rc, 0) << again.err;
  EXPECT_NE(again.out.find("resuming calibration 'resume'"), std::string::npos) << again.out;
  for (const auto& row : finished_before)
    EXPECT_EQ(scalar(db, "SELECT finished FROM runs WHERE id = " + row[0]), row[1])
        << "run " << row[0] << " was redone";
  // At most the one run in flight at the kill was started twice.
  EXPECT_LE(std::stoi(scalar(db, "SELECT sum(attempts) - count(*) FROM runs")), 1);
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs"), scalar(ref_db, "SELECT count(*) FROM runs"));

  const json a = load_json(dir / "ref" / "calibration.json"),
             b = load_json(dir / "killed" / "calibration.json");
  EXPECT_EQ(a["best"]["parameters"].dump(), b["best"]["parameters"].dump());
  EXPECT_EQ(a["best"]["terms"]["objective"].dump(), b["best"]["terms"]["objective"].dump());
  EXPECT_GE(b["evaluations"]["runs_read_back"].get<int>(), static_cast<int>(finished_before.size()));
  const std::string trace =
      "SELECT phase, start, seq, params, value FROM evaluations ORDER BY phase, start, seq";
  EXPECT_EQ(query(db, trace), query(ref_db, trace))
      << "the resumed trajectory differs from the uninterrupted one";
}

// The time shift is a parameter that needs no run: a target recorded 0.15 s late is matched by the shift,
// and points that differ only in the shift are looked up, not rerun.
TEST(CalibrateTwin, TimeShiftIsFittedWithoutRerunning) {
  const fs::path dir = test_dir();
  make_target(dir, {"reservoir.forcing.t99_s=0.8", "reservoir.gate_height_m=0.085"}, 0.5, 5, 7, 0.15);
  write_file(dir / "spec.json",
             two_parameter_spec(
                 "shift", R"({"name": "BOBYQA", "max_evaluations": 120})", R"(, "profile": {"points": 0})",
                 R"({"window": [0.5, 5], "time_shift": {"lower": -0.3, "upper": 0.3, "start": 0}})"));
  const fs::path out = dir / "out";
  const Result r = run(flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", (dir / "s.db").string(),
                                  "--out", out.string()}),
                       dir);
  ASSERT_EQ(r.rc, 0) << r.err;
  const json j = load_json(out / "calibration.json");
  EXPECT_NEAR(best(j, "objective.time_shift_s"), 0.15, 0.01);
  EXPECT_NEAR(best(j, kT99Path), kT99, 0.1 * kT99);
  EXPECT_NEAR(best(j, kGatePath), kGate, 0.1 * kGate);
  EXPECT_LT(j["evaluations"]["runs_in_store"].get<int>(), j["evaluations"]["optimizer"].get<int>());

  // The series posterior compares each run's record shifted as its evaluation was: the shift's interval too.
  const Result p = run(flume_cmd({"surrogate", "posterior", "--db", (dir / "s.db").string(), "--calibration",
                                  "shift", "--noise-m", std::to_string(kNoise_m)}),
                       dir);
  ASSERT_EQ(p.rc, 0) << p.err;
  std::printf("%s", p.out.c_str());
  for (const auto& [path, truth] :
       {std::pair{std::string(kT99Path), kT99}, std::pair{std::string(kGatePath), kGate},
        std::pair{std::string("objective.time_shift_s"), 0.15}}) {
    const auto [lo, hi] = posterior_interval(p.out, path);
    EXPECT_LE(lo, truth) << path;
    EXPECT_GE(hi, truth) << path;
  }
}

// Malformed specs and target records: exit 2 with the file and field (or line and column), before any run.
TEST(CalibrateInputs, MalformedSpecsAndRecordsExitTwoNamingTheField) {
  const fs::path dir = test_dir();
  write_file(dir / "target.csv", "time_s,WG1\n0,0\n1,0.01\n1,0.02\n5,0\n");
  auto calibrate = [&](const std::string& spec_text) {
    write_file(dir / "spec.json", spec_text);
    return run(flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", (dir / "s.db").string(), "--out",
                          (dir / "out").string()}),
               dir);
  };
  Result r = calibrate(two_parameter_spec("bad", R"({"name": "BOBYQA", "max_evaluations": 80})", ""));
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("target.csv: line 4, column 1 (time_s): repeats the time 1 s of line 3"),
            std::string::npos)
      << r.err;
  write_file(dir / "target.csv", "time_s,WG1\n0,0\n1,0.01\n2,x\n5,0\n");
  r = calibrate(two_parameter_spec("bad", R"({"name": "BOBYQA", "max_evaluations": 80})", ""));
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("target.csv: line 4, column 2 (WG1): 'x' is not a finite decimal number"),
            std::string::npos)
      << r.err;
  write_file(dir / "target.csv", "time_s,WG1\n0,0\n1,0.01\n2,0.02\n5,0\n");
  r = calibrate(two_parameter_spec("bad", R"({"name": "BOBYQA", "max_evaluations": 0})", ""));
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("spec.json: algorithm.max_evaluations: must be in [1, 1000000]"), std::string::npos)
      << r.err;
  r = calibrate(
      two_parameter_spec("bad", R"({"name": "BOBYQA", "max_evaluations": 5, "polish": "SBPLX"})", ""));
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("algorithm.polish: follows a global algorithm"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "s.db")) << "a refused spec must not create the store";
  for (const auto& e : {r.err}) EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << "one line: " << e;

  // A changed spec under a stored name is refused (its stored runs belong to the other spec).
  r = calibrate(two_parameter_spec("ok", R"({"name": "BOBYQA", "max_evaluations": 3})",
                                   R"(, "profile": {"points": 0})"));
  ASSERT_EQ(r.rc, 0) << r.err;
  r = calibrate(two_parameter_spec("ok", R"({"name": "SBPLX", "max_evaluations": 3})",
                                   R"(, "profile": {"points": 0})"));
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("spec.json: name: 'ok' is already in"), std::string::npos) << r.err;
  // A larger budget is not a change: the calibration continues.
  r = calibrate(two_parameter_spec("ok", R"({"name": "BOBYQA", "max_evaluations": 6})",
                                   R"(, "profile": {"points": 0})"));
  EXPECT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("resuming"), std::string::npos);
  EXPECT_EQ(scalar(dir / "s.db", "SELECT sum(attempts) FROM runs"),
            scalar(dir / "s.db", "SELECT count(*) FROM runs"));
}

// SIGTERM stops the calibration at once, also in the middle of a run: the run is killed and put back to
// pending, so the next job runs it (the store never holds a `running` run of a job that is gone).
TEST(CalibrateResume, SigtermKillsTheRunInFlightAndLeavesItPending) {
  const fs::path dir = test_dir();
  make_target(dir, {"reservoir.forcing.t99_s=0.8", "reservoir.gate_height_m=0.085"}, 0, 5);
  std::string spec = two_parameter_spec("term", R"({"name": "BOBYQA", "max_evaluations": 40})",
                                        R"(, "profile": {"points": 0})");
  const std::string model = R"("reservoir.forcing.model": "exponential")";
  spec.replace(spec.find(model), model.size(), model + R"(, "sleep_s": 30)");
  write_file(dir / "spec.json", spec);
  const fs::path db = dir / "s.db";
  const pid_t pid = spawn(flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", db.string(), "--out",
                                     (dir / "out").string()}),
                          dir / "t.out", dir / "t.err");
  ASSERT_GT(pid, 0);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < give_up &&
         scalar(db, "SELECT count(*) FROM runs WHERE status = 'running'") != "1")
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_EQ(scalar(db, "SELECT count(*) FROM runs WHERE status = 'running'"), "1");
  kill(pid, SIGTERM);
  EXPECT_EQ(wait_for(pid, 10), 128 + SIGTERM) << "a 30 s run must not delay the stop";
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs WHERE status = 'running'"), "0");
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM runs WHERE status = 'pending'"), "1");
  EXPECT_NE(read_file(dir / "t.err").find("run the same command again to resume"), std::string::npos);
}

// Issue 29: an --out folder that cannot be made is refused before the calibration runs anything (it used to
// run every evaluation and fail when writing calibration.json), in one line naming the folder and --out.
TEST(CalibrateInputs, UnwritableOutFolderIsRefusedBeforeAnyRun) {
  const fs::path dir = test_dir();
  write_file(dir / "target.csv", "time_s,WG1\n0,0\n1,0.01\n2,0.02\n5,0\n");
  write_file(dir / "spec.json", two_parameter_spec("out", R"({"name": "BOBYQA", "max_evaluations": 3})",
                                                   R"(, "profile": {"points": 0})"));
  write_file(dir / "plain-file", "not a folder\n");
  const std::string out = (dir / "plain-file" / "out").string();
  const Result r = run(
      flume_cmd({"calibrate", (dir / "spec.json").string(), "--db", (dir / "s.db").string(), "--out", out}), dir);
  EXPECT_EQ(r.rc, 2) << r.err;
  EXPECT_NE(r.err.find(out + ": --out: "), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  if (fs::exists(dir / "s.db")) {
    EXPECT_EQ(scalar(dir / "s.db", "SELECT count(*) FROM runs"), "0");
  }
  EXPECT_FALSE(fs::exists(dir / "s.db.runs" / "out" / "run-000000"));
}
