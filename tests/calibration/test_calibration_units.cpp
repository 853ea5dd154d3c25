// Calibration units: target-record checks (each refusal names file, line and column), the objective against
// hand-computed values, parameter scaling, spec refusals, and the store's calibration additions.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "calibration/objective.h"
#include "calibration/records.h"
#include "calibration/spec.h"
#include "common/errors.h"
#include "store/db/campaign_store.h"

namespace {

namespace fs = std::filesystem;
using namespace flume::calibration;

fs::path test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const fs::path dir = fs::temp_directory_path() / ("flume_calib_unit_" + std::to_string(getpid()) + "_" +
                                                    info->test_suite_name() + "_" + info->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string write(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
  return p.string();
}

// Runs f, expects an InputError whose field and message contain the given texts.
void expect_input_error(const std::function<void()>& f, const std::string& field,
                        const std::string& problem) {
  try {
    f();
    ADD_FAILURE() << "no error; expected " << field << ": " << problem;
  } catch (const flume::InputError& e) {
    EXPECT_NE(e.field().find(field), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line: " << e.what();
  }
}

const std::vector<std::string> kGauges = {"WG1", "WG2", "WG3", "WG4"};

std::vector<TargetRecord> read(const std::string& file, double t0 = 0.0, double t1 = 0.03) {
  return read_target_csv(file, {}, kGauges, t0, t1, 1.0, "targets.0");
}

}  // namespace

TEST(TargetRecords, ReadsColumnsPerGaugeWithUnits) {
  const auto dir = test_dir();
  const auto f = write(dir / "t.csv",
                       "# a comment\ntime [ms],WG1,WG2 [mm]\n0,0.01,10\n10,0.02,20\n\n20,0.03,30\n30,0,0\n");
  const auto r = read(f);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].gauge, "WG1");
  EXPECT_EQ(r[1].gauge, "WG2");
  EXPECT_DOUBLE_EQ(r[0].time[2], 0.02);
  EXPECT_DOUBLE_EQ(r[1].elevation[1], 0.02);  // 20 mm
}

TEST(TargetRecords, EachMalformedFileIsRefusedWithLineAndColumn) {
  const auto dir = test_dir();
  const std::string head = "time_s,WG1\n";
  expect_input_error([&] { read(write(dir / "a.csv", head + "0,0\n0.02,0\n0.01,0\n0.03,0\n")); },
                     "line 4, column 1 (time_s)", "times must be sorted");
  expect_input_error([&] { read(write(dir / "b.csv", head + "0,0\n0.01,0\n0.01,0\n0.03,0\n")); },
                     "line 4, column 1 (time_s)", "repeats the time 0.01 s of line 3");
  expect_input_error([&] { read(write(dir / "c.csv", head + "0,0\n0.01,abc\n0.03,0\n")); },
                     "line 3, column 2 (WG1)", "'abc' is not a finite decimal number");
  expect_input_error([&] { read(write(dir / "d.csv", head + "0,0\n0.01,nan\n0.03,0\n")); },
                     "line 3, column 2 (WG1)", "'nan' is not a finite decimal number");
  expect_input_error([&] { read(write(dir / "e.csv", head + "0,0\n0.01\n0.03,0\n")); }, "line 3",
                     "has 1 cells but the header has 2 columns");
  expect_input_error([&] { read(write(dir / "f.csv", head + "0,0\n0.01,\n0.03,0\n")); },
                     "line 3, column 2 (WG1)", "is empty");
  expect_input_error([&] { read(write(dir / "g.csv", "time_s,WG9\n0,0\n0.03,0\n")); },
                     "line 1, column 2 (WG9)",
                     "'WG9' is not a gauge of the scene (its gauges: WG1, WG2, WG3, WG4)");
  expect_input_error([&] { read(write(dir / "h.csv", head + "0,0\n0.02,0\n")); }, "",
                     "time span [0, 0.02] s does not cover objective.window [0, 0.03] s");
  expect_input_error([&] { read(write(dir / "i.csv", head + "0,0\n0.01,85\n0.03,0\n")); },
                     "line 3, column 2 (WG1)", "is the column in mm or cm");
  expect_input_error([&] { read(write(dir / "j.csv", "time [min],WG1\n0,0\n0.03,0\n")); }, "line 1, column 1",
                     "time unit must be s or ms");
  expect_input_error([&] { read(write(dir / "k.csv", "seconds,WG1\n0,0\n0.03,0\n")); }, "line 1, column 1",
                     "the first column must be time");
  expect_input_error([&] { read(write(dir / "l.csv", "")); }, "", "is empty");
  expect_input_error(
      [&] {
        read_target_csv(write(dir / "m.csv", head + "0,0\n0.03,0\n"), {{"WG2", "eta2"}}, kGauges, 0, 0.03,
                        1.0, "targets.3");
      },
      "line 1", "has no column 'eta2' (mapped to gauge WG2 by targets.3.gauges)");
}

TEST(Objective, HandComputedTerms) {
  // Target: a triangle 0 -> 0.1 m -> 0 over [0, 2] s sampled every 0.01 s.
  TargetRecord t;
  t.gauge = "WG1";
  for (int k = 0; k <= 200; ++k) {
    t.time.push_back(k * 0.01);
    t.elevation.push_back(k <= 100 ? 0.001 * k : 0.001 * (200 - k));
  }
  ObjectiveSpec spec;
  spec.window_start_s = 0;
  spec.window_end_s = 2;
  spec.peak_weight = 0.5;
  spec.arrival_weight_m_per_s = 0.1;
  spec.arrival_threshold_m = 0.0055;  // crossed between samples 5 and 6, at 0.055 s
  Objective objective(spec, {t}, "spec.json");
  ASSERT_TRUE(objective.windows()[0].arrival_s.has_value());
  EXPECT_NEAR(*objective.windows()[0].arrival_s, 0.055, 1e-12);

  SimRecord same{t.time, t.elevation};
  auto terms = objective.evaluate({{"WG1", same}}, 0.0);
  EXPECT_NEAR(terms.value, 0.0, 1e-15);

  // 1 cm higher everywhere: RMS 0.01, peak error 0.01, arrival earlier by 0.01 m / (0.1 m/s) = 0.1 s.
  SimRecord up = same;
  for (auto& e : up.elevation) e += 0.01;
  terms = objective.evaluate({{"WG1", up}}, 0.0);
  EXPECT_NEAR(terms.rms_m, 0.01, 1e-12);
  EXPECT_NEAR(terms.peak_error_m, 0.01, 1e-12);
  EXPECT_NEAR(terms.arrival_error_s, 0.055, 1e-12);  // the raised record starts above the threshold at t = 0
  EXPECT_NEAR(terms.value, 0.01 + 0.5 * 0.01 + 0.1 * 0.055, 1e-12);

  // A simulation 0.2 s early is matched exactly by a shift of +0.2 s (the signal is linear between samples).
  SimRecord early{{}, {}};
  for (int k = -50; k <= 200; ++k) {
    const double tt = k * 0.01;
    early.time.push_back(tt);
    const int kk = k + 20;
    early.elevation.push_back(kk < 0 ? 0.0
                                     : (kk <= 100 ? 0.001 * kk : (kk <= 200 ? 0.001 * (200 - kk) : 0.0)));
  }
  EXPECT_GT(objective.evaluate({{"WG1", early}}, 0.0).value, 0.01);
  EXPECT_NEAR(objective.evaluate({{"WG1", early}}, 0.2).value, 0.0, 1e-12);

  // A failed run scores twice a simulation at still water.
  SimRecord still{{0.0, 2.0}, {0.0, 0.0}};
  EXPECT_NEAR(objective.failure("x").value, 2 * objective.evaluate({{"WG1", still}}, 0.0).value, 1e-15);
}

TEST(Parameters, UnitScalingRoundTrips) {
  FreeParameter lin{"a", 0.04, 0.16, 0.1};
  EXPECT_NEAR(lin.to_unit(0.1), 0.5, 1e-15);
  EXPECT_NEAR(lin.from_unit(0.25), 0.07, 1e-15);
  FreeParameter lg{"b", 0.1, 10.0, 1.0, Scale::kLog};
  EXPECT_NEAR(lg.to_unit(1.0), 0.5, 1e-15);
  EXPECT_NEAR(lg.from_unit(lg.to_unit(0.37)), 0.37, 1e-14);
}

TEST(Spec, RefusalsNameTheField) {
  const auto dir = test_dir();
  write(dir / "wg1.csv", "time_s,WG1\n0,0\n1,0.05\n2,0\n");
  const std::string good_params =
      R"([{"path": "reservoir.forcing.t99_s", "lower": 0.05, "upper": 2, "start": 0.2},
          {"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.12}])";
  auto spec = [&](const std::string& params, const std::string& algorithm, const std::string& extra = "") {
    return R"({"name": "s", "model": "gauge", "targets": [{"file": "wg1.csv"}], "parameters": )" + params +
           R"(, "objective": {"window": [0, 2]}, "algorithm": )" + algorithm + extra + "}";
  };
  auto parse = [&](const std::string& text) {
    return parse_calibration_spec(text, "spec.json", dir.string());
  };
  const std::string bobyqa = R"({"name": "BOBYQA", "max_evaluations": 80})";
  const std::string sbplx = R"({"name": "SBPLX", "max_evaluations": 80})";
  EXPECT_NO_THROW(parse(spec(good_params, bobyqa)));
  expect_input_error([&] { parse(spec(good_params, R"({"name": "LBFGS", "max_evaluations": 80})")); },
                     "algorithm.name",
                     "must be one of BOBYQA|COBYLA|NELDERMEAD|SBPLX|CRS2_LM|DIRECT_L|ISRES|MLSL");
  expect_input_error([&] { parse(spec(good_params, R"({"name": "MLSL", "max_evaluations": 80})")); },
                     "algorithm.local", "is required");
  expect_input_error([&] { parse(spec(good_params, R"({"name": "BOBYQA"})")); }, "algorithm.max_evaluations",
                     "is required");
  expect_input_error(
      [&] {
        parse(spec(R"([{"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.1}])",
                   bobyqa));
      },
      "algorithm.name", "BOBYQA needs at least 2 free parameters");
  expect_input_error(
      [&] {
        parse(spec(R"([{"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.3}])",
                   bobyqa));
      },
      "parameters.0.start", "must be in [0.04, 0.16]");
  expect_input_error(
      [&] {
        parse(spec(R"([{"path": "reservoir.gate_height", "lower": 0.04, "upper": 0.16, "start": 0.1}])",
                   sbplx));
      },
      "parameters.0", "not an input of model gauge");
  expect_input_error(
      [&] {
        parse(spec(R"([{"path": "reservoir.gate_height_m", "lower": 0.0, "upper": 0.16, "start": 0.1}])",
                   sbplx));
      },
      "parameters.0", "must be a number in (0, 0.5]");
  expect_input_error([&] { parse(spec(good_params, bobyqa, R"(, "profile": {"pionts": 3})")); },
                     "profile.pionts", "unknown field");
  expect_input_error([&] { parse(spec(good_params, bobyqa, R"(, "overrides": {"solver.end_time": 1.5})")); },
                     "objective.window", "the simulation records only to 1.5 s");
  expect_input_error(
      [&] {
        parse(
            R"({"name": "s", "model": "gauge", "targets": [{"file": "wg1.csv", "gauge": "WG7"}], "parameters": )" +
            good_params + R"(, "objective": {"window": [0, 2]}, "algorithm": )" + bobyqa + "}");
      },
      "targets.0.gauge", "'WG7' is not a gauge of the model");
  expect_input_error(
      [&] {
        parse(
            R"({"name": "s", "model": "gauge", "targets": [{"file": "wg1.csv"}], "parameters": )" +
            good_params +
            R"(, "objective": {"window": [0, 2], "arrival_weight_m_per_s": 1, "arrival_threshold_m": 0.2}, "algorithm": )" +
            bobyqa + "}");
      },
      "objective.arrival_weight_m_per_s", "never reaches arrival_threshold_m");
  expect_input_error([&] { parse("{\"name\": \"s\",}"); }, "", "not valid JSON");
}

// objective.stages, the window continuation: end times strictly inside the window and increasing, a local
// algorithm, and every stage able to score the objective it weights (an arrival inside each stage).
TEST(Spec, WindowContinuationStagesAreCheckedAndPartOfTheIdentity) {
  const auto dir = test_dir();
  write(dir / "wg1.csv", "time_s,WG1\n0,0\n1,0.05\n2,0\n");
  auto spec = [&](const std::string& objective, const std::string& algorithm = "BOBYQA") {
    return R"({"name": "s", "model": "gauge", "targets": [{"file": "wg1.csv"}], "parameters":
      [{"path": "reservoir.forcing.t99_s", "lower": 0.05, "upper": 2, "start": 0.2},
       {"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.12}],
      "objective": )" +
           objective + R"(, "algorithm": {"name": ")" + algorithm + R"(", "max_evaluations": 80}})";
  };
  auto parse = [&](const std::string& text) {
    return parse_calibration_spec(text, "spec.json", dir.string());
  };
  const auto plain = parse(spec(R"({"window": [0, 2]})"));
  const auto staged = parse(spec(R"({"window": [0, 2], "stages": [1.0, 1.5]})"));
  EXPECT_TRUE(plain.objective.stage_end_s.empty());
  EXPECT_EQ(staged.objective.stage_end_s, (std::vector<double>{1.0, 1.5}));
  EXPECT_NE(plain.hash, staged.hash)
      << "stages change the optimizer's path: a stored calibration must refuse them";
  EXPECT_EQ(staged.algorithm.stage_step, 0.01);
  expect_input_error([&] { parse(spec(R"({"window": [0, 2], "stages": [2.5]})")); }, "objective.stages",
                     "each inside the window (0, 2)");
  expect_input_error([&] { parse(spec(R"({"window": [0, 2], "stages": [2]})")); }, "objective.stages",
                     "each inside the window");
  expect_input_error([&] { parse(spec(R"({"window": [0, 2], "stages": [1.5, 1.0]})")); }, "objective.stages",
                     "must be increasing");
  expect_input_error([&] { parse(spec(R"({"window": [0, 2], "stages": ["1"]})")); }, "objective.stages",
                     "must be increasing");
  expect_input_error([&] { parse(spec(R"({"window": [0, 2], "stages": 1})")); }, "objective.stages",
                     "must be an array");
  expect_input_error([&] { parse(spec(R"({"window": [0, 2], "stages": [1]})", "CRS2_LM")); },
                     "algorithm.name", "needs a local algorithm");
  expect_input_error(
      [&] {
        parse(spec(
            R"({"window": [0, 2], "stages": [0.5], "arrival_weight_m_per_s": 1, "arrival_threshold_m": 0.01})"));
      },
      "objective.stages", "the stage ending at 0.5 s");
}

TEST(Store, CalibrationRunsAreAddedOnceAndEvaluationsReplace) {
  const auto dir = test_dir();
  flume::store::CampaignStore db((dir / "s.db").string());
  flume::store::CampaignRecord rec;
  rec.name = "c";
  rec.spec = "{}";
  rec.spec_hash = "h";
  rec.code_version = "test";
  const auto campaign = db.create_campaign(rec, {{"a", false}}, {});
  flume::store::PlannedRun r1{0, "hash1", R"({"a":1})", {{false, 1.0, ""}}};
  flume::store::PlannedRun r2{0, "hash2", R"({"a":2})", {{false, 2.0, ""}}};
  const auto id1 = db.add_run(campaign, r1);
  EXPECT_EQ(db.add_run(campaign, r1), id1);  // a repeated point is the same run
  const auto id2 = db.add_run(campaign, r2);
  EXPECT_NE(id1, id2);
  EXPECT_EQ(db.find_run(campaign, "hash2")->design_index, 1);
  EXPECT_FALSE(db.find_run(campaign, "hash3").has_value());
  const auto ticket = db.claim_run(id1, "host", "w");
  EXPECT_EQ(ticket.attempt, 1);
  EXPECT_THROW(db.claim_run(id1, "host", "w"), flume::store::StoreError);  // not pending any more
  flume::store::RunOutcome o;
  o.status = flume::store::RunStatus::kOk;
  db.record_outcome(id1, o);
  EXPECT_EQ(db.find_run(campaign, "hash1")->status, flume::store::RunStatus::kOk);
  flume::store::Evaluation e{"optimize", 0, 0, id1, R"({"a":1})", 0.5, "{}"};
  db.record_evaluation(campaign, e);
  e.value = 0.25;
  db.record_evaluation(campaign,
                       e);  // the same (phase, start, seq): replaced, as a replay after a restart does
  const auto all = db.evaluations(campaign);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all[0].value, 0.25);
  EXPECT_EQ(db.integrity_check(), "ok");
}
