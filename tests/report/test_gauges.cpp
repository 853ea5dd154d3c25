// `flume gauges`: two synthetic runs (sine and ramp records with known peaks and arrivals, written with the
// solver's HDF5 writer, no solver run): the SVG's panels, lines and labels, the printed numbers, the natural
// order of the gauges, --t-max, and the input errors (exit 2, naming the file and the gauge or option).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "common/plot/figure.h"
#include "tests/common/run_command.h"
#include "report/gauge_band.h"
#include "report/gauges.h"
#include "common/gauge_summary.h"
#include "store/h5/run_file.h"


namespace {

namespace fs = std::filesystem;
constexpr double kPi = 3.14159265358979323846;


using Result = flume::test::CommandResult;
using flume::test::read_file;
Result run(const std::vector<std::string>& args, const fs::path& dir) { return flume::test::run_command(args, dir); }

// A record sampled at 100 Hz over [0, t_end].
void write_gauge(flume::h5::RunFile& f, const std::string& name, double t_end, const std::function<double(double)>& eta) {
  std::vector<double> t, e;
  for (int i = 0; i <= static_cast<int>(std::lround(t_end * 100)); ++i) {
    t.push_back(i / 100.0);
    e.push_back(eta(i / 100.0));
  }
  f.write_series("/gauges/" + name, "time", t);
  f.write_series("/gauges/" + name, "elevation", e);
}

class GaugesCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("flume_gauges_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "run_a");
    fs::create_directories(dir_ / "run_b");
    {
      // run_a: WG1 0.1 sin(pi t / 4) over 4 s (peak 0.1 m at 2 s; 5 mm first reached at 0.07 s); WG2 a ramp
      // from a dry 0.02 m, slope 0.04 m/s from 1 s (peak 0.1 m at 3 s; +5 mm after 0.125 s: 1.13 s).
      flume::h5::RunFile f((dir_ / "run_a" / "result.h5").string());
      write_gauge(f, "WG2", 3, [](double t) { return 0.02 + 0.04 * std::max(0.0, t - 1); });
      write_gauge(f, "WG1", 4, [](double t) { return 0.1 * std::sin(kPi * t / 4); });
      f.finalize();
    }
    {
      // run_b: WG1 0.08 sin(pi (t - 0.5) / 4) from 0.5 s (peak 0.08 m at 2.5 s; arrival 0.58 s); WG2 from
      // 0.02 m, slope 0.03 m/s from 1.5 s (peak 0.065 m at 3 s; arrival 1.67 s); WG10 and WG3 flat (never
      // arrive), written in that order.
      flume::h5::RunFile f((dir_ / "run_b" / "result.h5").string());
      write_gauge(f, "WG1", 4, [](double t) { return t < 0.5 ? 0.0 : 0.08 * std::sin(kPi * (t - 0.5) / 4); });
      write_gauge(f, "WG2", 3, [](double t) { return 0.02 + 0.03 * std::max(0.0, t - 1.5); });
      write_gauge(f, "WG10", 1, [](double) { return 0.001; });
      write_gauge(f, "WG3", 1, [](double) { return 0.0; });
      f.finalize();
    }
  }
  void TearDown() override { fs::remove_all(dir_); }
  Result gauges(std::vector<std::string> args) {
    args.insert(args.begin(), {FLUME_EXE, "gauges"});
    return run(args, dir_);
  }
  std::string a() const { return (dir_ / "run_a").string(); }
  std::string b() const { return (dir_ / "run_b").string(); }
  fs::path dir_;
};

// The data lines (a path with line segments, not a legend swatch) of colour `hex` in one panel.
int data_lines(const std::string& panel, const std::string& hex) {
  const std::regex line("<path d=\"M[^\"]*L[^\"]*\" fill=\"none\" stroke=\"" + hex + "\"");
  return static_cast<int>(std::distance(std::sregex_iterator(panel.begin(), panel.end(), line), std::sregex_iterator()));
}

std::vector<std::string> panels(const std::string& svg) {
  std::vector<std::string> out;
  const std::string marker = "<g class=\"axes\">";
  std::size_t at = svg.find(marker);
  while (at != std::string::npos) {
    const std::size_t next = svg.find(marker, at + marker.size());
    out.push_back(svg.substr(at, next == std::string::npos ? std::string::npos : next - at));
    at = next;
  }
  return out;
}

TEST_F(GaugesCli, PlotsEveryGaugeOfTheFirstRunWithOneLinePerRun) {
  const fs::path svg = dir_ / "g.svg";
  const Result r = gauges({a() + "=sine & ramp", b(), "--out", svg.string(), "--title", "two runs"});
  ASSERT_EQ(r.rc, 0) << r.err;
  ASSERT_TRUE(fs::exists(svg));
  const std::string text = read_file(svg);
  const std::vector<std::string> p = panels(text);
  ASSERT_EQ(p.size(), 2u);  // WG1, WG2: run_a's gauges (run_b's extra WG3 and WG10 are not asked for)
  for (const std::string& panel : p) {
    EXPECT_EQ(data_lines(panel, flume::plot::palette(0).hex()), 1);
    EXPECT_EQ(data_lines(panel, flume::plot::palette(1).hex()), 1);
    EXPECT_NE(panel.find("eta (m)"), std::string::npos);
  }
  EXPECT_LT(p[0].find(">WG1<"), p[0].size());
  EXPECT_LT(p[1].find(">WG2<"), p[1].size());
  EXPECT_NE(p[1].find("t (s)"), std::string::npos);
  EXPECT_NE(text.find("sine &amp; ramp"), std::string::npos);  // the label, escaped
  EXPECT_NE(text.find(">run_b<"), std::string::npos);           // the folder's name by default
  EXPECT_NE(text.find("two runs"), std::string::npos);

  // The known peaks and arrivals, gauge by gauge and in the runs' order.
  const std::string expected =
      "WG1 sine & ramp: peak 0.1000 m at 2.000 s, arrival 0.070 s (5 mm above the first reading, 0.0000 m)\n"
      "WG1 run_b: peak 0.0800 m at 2.500 s, arrival 0.580 s (5 mm above the first reading, 0.0000 m)\n"
      "WG2 sine & ramp: peak 0.1000 m at 3.000 s, arrival 1.130 s (5 mm above the first reading, 0.0200 m)\n"
      "WG2 run_b: peak 0.0650 m at 3.000 s, arrival 1.670 s (5 mm above the first reading, 0.0200 m)\n"
      "wrote " + svg.string() + "\n";
  EXPECT_EQ(r.out, expected);
}

TEST_F(GaugesCli, GaugeListTimeLimitAndNaturalOrder) {
  const fs::path svg = dir_ / "g.svg";
  Result r = gauges({a(), "--gauges", "WG1", "--t-max", "1.5", "--out", svg.string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(panels(read_file(svg)).size(), 1u);
  // 0.1 sin(3 pi / 8) = 0.092388 at the window's end.
  EXPECT_NE(r.out.find("WG1 run_a: peak 0.0924 m at 1.500 s, arrival 0.070 s"), std::string::npos) << r.out;

  r = gauges({b(), "--out", svg.string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  const std::size_t g1 = r.out.find("WG1 "), g2 = r.out.find("WG2 "), g3 = r.out.find("WG3 "), g10 = r.out.find("WG10 ");
  ASSERT_NE(g10, std::string::npos) << r.out;
  EXPECT_LT(g1, g2);
  EXPECT_LT(g2, g3);
  EXPECT_LT(g3, g10);
  EXPECT_NE(r.out.find("WG3 run_b: peak 0.0000 m at 0.000 s, arrival none"), std::string::npos) << r.out;
  EXPECT_EQ(panels(read_file(svg)).size(), 4u);
}

TEST_F(GaugesCli, InputErrorsExitTwoNamingTheFileAndGauge) {
  const std::string svg = (dir_ / "x.svg").string();
  // run_a has no WG3.
  Result r = gauges({b(), a(), "--gauges", "WG1,WG3", "--out", svg});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find((dir_ / "run_a" / "result.h5").string() + ": /gauges/WG3: missing"), std::string::npos) << r.err;
  // Nor by default: the gauges are the first run's (run_b: WG1, WG2, WG3, WG10), and run_a lacks WG3 first.
  r = gauges({b(), a(), "--out", svg});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("run_a/result.h5: /gauges/WG3: missing"), std::string::npos) << r.err;

  fs::create_directories(dir_ / "unfinished");
  r = gauges({a(), (dir_ / "unfinished").string(), "--out", svg});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find((dir_ / "unfinished" / "result.h5").string() + ": missing"), std::string::npos) << r.err;

  r = gauges({(dir_ / "nope").string(), "--out", svg});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find((dir_ / "nope").string() + ": no such run folder"), std::string::npos) << r.err;

  r = gauges({a(), "--out", svg, "--colour", "red"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("flume gauges: --colour: unknown option"), std::string::npos) << r.err;

  r = gauges({a()});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("flume gauges: --out: is required"), std::string::npos) << r.err;

  r = gauges({a(), "--out", svg, "--t-max", "-1"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("--t-max: '-1'"), std::string::npos) << r.err;

  EXPECT_FALSE(fs::exists(svg));
}

// Pressure probes (issue 30): a triangular pulse of 1000 Pa, 0.02 s wide at its base, at 0.05 s, sampled at
// 1 kHz (impulse 1000 Pa x 0.01 s = 10 Pa s), gets a panel after the gauges and a line with its peak and
// impulse; a run with pressure probes and no gauges plots them alone.
TEST_F(GaugesCli, PressureProbesAfterTheGauges) {
  for (const char* run : {"run_c", "run_d"}) {
    fs::create_directories(dir_ / run);
    flume::h5::RunFile f((dir_ / run / "result.h5").string());
    if (std::string(run) == "run_c") write_gauge(f, "WG1", 0.1, [](double t) { return 0.01 * t; });
    std::vector<double> t, p;
    for (int i = 0; i <= 100; ++i) {
      t.push_back(i / 1000.0);
      p.push_back(1000 * std::max(0.0, 1 - std::fabs(i - 50) / 10.0));
    }
    f.write_series("/pressure_probes/PS1", "time", t);
    f.write_series("/pressure_probes/PS1", "pressure", p);
    f.finalize();
  }
  const fs::path svg = dir_ / "p.svg";
  Result r = gauges({(dir_ / "run_c").string(), "--out", svg.string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  std::vector<std::string> p = panels(read_file(svg));
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NE(p[0].find("eta (m)"), std::string::npos);
  EXPECT_NE(p[1].find("p (Pa)"), std::string::npos);
  EXPECT_LT(p[1].find(">PS1<"), p[1].size());
  EXPECT_NE(r.out.find("PS1 run_c: peak 1000.0 Pa at 0.0500 s, impulse 10.000 Pa s\n"), std::string::npos) << r.out;
  EXPECT_LT(r.out.find("WG1 run_c"), r.out.find("PS1 run_c"));

  r = gauges({(dir_ / "run_d").string(), "--gauges", "PS1", "--out", svg.string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(panels(read_file(svg)).size(), 1u);
  EXPECT_NE(r.out.find("PS1 run_d: peak 1000.0 Pa"), std::string::npos) << r.out;
}

// `flume export --csv` writes the pressure probes beside the gauges, one row per sample.
TEST_F(GaugesCli, ExportWritesPressureProbes) {
  fs::create_directories(dir_ / "run_p");
  {
    flume::h5::RunFile f((dir_ / "run_p" / "result.h5").string());
    write_gauge(f, "WG1", 0.02, [](double) { return 0.0; });
    f.write_series("/pressure_probes/PS1", "time", {0.0, 0.001, 0.002});
    f.write_series("/pressure_probes/PS1", "pressure", {0.0, 12.5, 0.25});
    f.finalize();
  }
  const Result r = run({FLUME_EXE, "export", (dir_ / "run_p").string(), "--csv", (dir_ / "csv").string()}, dir_);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(read_file(dir_ / "csv" / "pressure_probes.csv"), "name,time,pressure\nPS1,0,0\nPS1,0.001,12.5\nPS1,0.002,0.25\n");
  EXPECT_TRUE(fs::exists(dir_ / "csv" / "gauges.csv"));
}

TEST(PressureSummary, PeakTimeAndImpulseSkipNonFiniteSamples) {
  const double nan = std::nan("");
  // Each sample is the mean over the interval before it: impulse 0.5 x 1 + 2 x 1 + 1 x 2 (the NaN's interval
  // is lost with it).
  const auto s = flume::summarize_pressure({0, 1, 2, 3, 5}, {0, 0.5, 2, nan, 1});
  EXPECT_DOUBLE_EQ(s.peak, 2);
  EXPECT_DOUBLE_EQ(s.peak_time, 2);
  EXPECT_DOUBLE_EQ(s.impulse, 0.5 + 2 + 2);
  EXPECT_DOUBLE_EQ(flume::summarize_pressure({}, {}).peak, 0);
}

TEST(GaugeSummary, PeakAndArrivalSkipNonFiniteSamples) {
  const double nan = std::nan("");
  const auto s = flume::summarize_gauge({0, 1, 2, 3, 4}, {nan, 0.25, 0.252, nan, 0.3}, 0.005);
  EXPECT_TRUE(s.has_peak);
  EXPECT_DOUBLE_EQ(s.first, 0.25);
  EXPECT_DOUBLE_EQ(s.peak, 0.3);
  EXPECT_DOUBLE_EQ(s.peak_time, 4);
  EXPECT_TRUE(s.arrived);
  EXPECT_DOUBLE_EQ(s.arrival_time, 4);
  EXPECT_FALSE(flume::summarize_gauge({0, 1}, {nan, nan}, 0.005).has_peak);
}

TEST(GaugeNames, NaturalOrder) {
  std::vector<std::string> names = {"WG10", "WG2", "WG1", "probe", "WG3"};
  flume::report::sort_gauge_names(names);
  EXPECT_EQ(names, (std::vector<std::string>{"WG1", "WG2", "WG3", "WG10", "probe"}));
}

}  // namespace

namespace {

// Type-7 quantiles (Hyndman & Fan 1996), by hand: p (n - 1) = h, value x[floor h] + frac(h) (x[ceil h] - ...).
TEST(GaugeBand, SampleQuantileInterpolatesBetweenOrderStatistics) {
  std::vector<double> v{3, 1, 2, 4};
  EXPECT_DOUBLE_EQ(flume::report::sample_quantile(v, 0.1), 1.3);
  EXPECT_DOUBLE_EQ(flume::report::sample_quantile(v, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(flume::report::sample_quantile(v, 1.0), 4.0);
  std::vector<double> none;
  EXPECT_TRUE(std::isnan(flume::report::sample_quantile(none, 0.5)));
}

// Five records k + t (k = 0..4) on one time grid, and one that starts later: at each time the 50 % band is
// the 25 and 75 % quantiles of the records covering it (1 + t and 3 + t while the sixth is absent).
TEST(GaugeBand, QuantilesAtEachTimeOfTheRecordsCoveringIt) {
  std::vector<flume::report::TimeSeries> r;
  for (int k = 0; k < 5; ++k) r.push_back({{0, 1, 2}, {k + 0.0, k + 1.0, k + 2.0}});
  r.push_back({{1.5, 2}, {100, 100}});  // covers t = 2 only of the first record's times
  const auto b = flume::report::gauge_band(r, 0.5);
  ASSERT_EQ(b.time.size(), 3u);
  EXPECT_DOUBLE_EQ(b.lo[0], 1.0);
  EXPECT_DOUBLE_EQ(b.median[0], 2.0);
  EXPECT_DOUBLE_EQ(b.hi[1], 4.0);
  // t = 2: values 2, 3, 4, 5, 6, 100: the 25 % quantile at h = 1.25 is 3.25, the median 4.5, the 75 % 5.75.
  EXPECT_DOUBLE_EQ(b.lo[2], 3.25);
  EXPECT_DOUBLE_EQ(b.median[2], 4.5);
  EXPECT_DOUBLE_EQ(b.hi[2], 5.75);
}

}  // namespace

// The two runs as a band with one of them on top: the band's peaks and arrivals are the quantiles of the
// runs' own (0.1 and 0.08 m, 0.07 and 0.58 s), and the line keeps its own summary line.
TEST_F(GaugesCli, BandOfRunsWithALineOnTop) {
  const fs::path svg = dir_ / "band.svg";
  const Result r = gauges({a(), b(), "--band", "--line", a() + "=reference", "--gauges", "WG1", "--out", svg.string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("WG1 band of 2 runs: peak median 0.0900 [0.0805, 0.0995] m, arrival in 2: median 0.325 "
                       "[0.083, 0.567] s (95 % of the runs between the brackets)\n"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("WG1 reference: peak 0.1000 m at 2.000 s"), std::string::npos) << r.out;
  const std::string text = read_file(svg);
  EXPECT_NE(text.find("95 % of 2 runs"), std::string::npos);
  EXPECT_EQ(data_lines(panels(text)[0], flume::plot::palette(1).hex()), 1);  // the reference, after the band

  EXPECT_EQ(gauges({a(), "--band", "--out", svg.string()}).rc, 2) << "a band needs two runs";
  EXPECT_EQ(gauges({a(), b(), "--line", a(), "--out", svg.string()}).rc, 2) << "--line goes with --band";
}
