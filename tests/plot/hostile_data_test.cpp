// Data that once sent the tick loop into an unbounded allocation (issue 29): constant, constant up to
// rounding, huge, many decades, non-finite. Each must give a bounded axis with a handful of ticks.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "common/plot/figure.h"
#include "tests/plot/xml_check.h"

using namespace flume::plot;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

#if defined(__SANITIZE_ADDRESS__)
#define FLUME_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FLUME_ASAN 1
#endif
#endif

// Runs `check` in a child process with 2 GiB of address space, so that a tick loop that never ends fails
// with bad_alloc in a second instead of taking the machine's memory (the old code grew to 32 GB).
// AddressSanitizer reserves terabytes of shadow memory, so under it the limit is left off.
template <class Check>
[[noreturn]] void run_bounded(Check check) {
#ifndef FLUME_ASAN
  const rlim_t two_gib = rlim_t{2} << 30;
  rlimit lim{two_gib, two_gib};
  setrlimit(RLIMIT_AS, &lim);
#endif
  try {
    std::exit(check() ? 0 : 3);
  } catch (...) {
    std::exit(4);
  }
}

template <class Check>
void in_bounded_child(Check check) {
  EXPECT_EXIT(run_bounded(check), ::testing::ExitedWithCode(0), "");
}

// A sane axis: finite limits around the data, 2..12 evenly spaced ticks on the limits.
bool sane(const NiceAxis& a, double data_lo, double data_hi) {
  if (!std::isfinite(a.lo) || !std::isfinite(a.hi) || !(a.lo < a.hi)) return false;
  if (a.ticks.size() < 2 || a.ticks.size() > 12) return false;
  if (a.ticks.front() != a.lo || a.ticks.back() != a.hi) return false;
  // Data within rounding (1e-9 of a step) of a tick count as on it.
  double step = a.ticks[1] - a.ticks[0];
  if (a.lo > data_lo + 1e-9 * step || a.hi < data_hi - 1e-9 * step) return false;
  for (std::size_t i = 1; i < a.ticks.size(); ++i)
    if (!(std::abs(a.ticks[i] - a.ticks[i - 1] - step) <= 1e-6 * step)) return false;
  return true;
}

bool axis_ok(double lo, double hi) { return sane(nice_axis(lo, hi), lo, hi); }

// A figure of y against x renders to well-formed SVG without "nan" or "inf" coordinates.
bool figure_ok(const std::vector<double>& x, const std::vector<double>& y) {
  Figure fig;
  fig.axes().line(x, y).scatter(x, y);
  std::string svg = fig.to_svg();
  return flume::plot::test::check_xml(svg).error.empty() && svg.find("nan") == std::string::npos &&
         svg.find("inf") == std::string::npos && svg.size() < 100000;
}

TEST(HostileData, ConstantUpToRounding) {
  // WG2.peak_time_s of the demo: the same time from eight runs, a few ulps apart.
  double t = 3.27;
  double t1 = std::nextafter(t, 4.0), t2 = std::nextafter(t1, 4.0);
  in_bounded_child([&] { return axis_ok(t, t1) && axis_ok(t, t2) && axis_ok(-t2, -t); });
  in_bounded_child([&] { return figure_ok({0, 1, 2}, {t, t1, t2}); });
  // Float noise at single precision is a real (tiny) range: still a handful of ticks.
  in_bounded_child([] { return axis_ok(3.2699998, 3.2700002); });
}

TEST(HostileData, ExactlyConstant) {
  in_bounded_child([] { return axis_ok(3.27, 3.27) && axis_ok(0, 0) && axis_ok(-1e-300, -1e-300); });
  in_bounded_child([] { return figure_ok({1, 1, 1}, {2, 2, 2}); });
}

TEST(HostileData, Huge) {
  in_bounded_child([] { return axis_ok(1e300, 1e300) && axis_ok(-1e300, 1e300) && axis_ok(1e300, 1.0000001e300); });
  in_bounded_child([] { return figure_ok({0, 1}, {1e300, 1e300}) && figure_ok({-1e300, 1e300}, {0, 1}); });
  // Beyond the clamp (+-1e307) the axis stays finite; the extreme points lie outside it.
  in_bounded_child([] {
    NiceAxis a = nice_axis(-1.7e308, 1.7e308);
    return std::isfinite(a.lo) && std::isfinite(a.hi) && a.ticks.size() <= 12 &&
           figure_ok({0, 1}, {-1.7e308, 1.7e308});
  });
}

TEST(HostileData, Tiny) {
  // Subnormal data: a step 10^e with e < -307 would underflow to ticks that are all zero.
  in_bounded_child([] { return axis_ok(1e-320, 3e-320) && axis_ok(0, 5e-324); });
  in_bounded_child([] { return figure_ok({0, 1}, {1e-320, 3e-320}); });
}

TEST(HostileData, ManyDecades) {
  in_bounded_child([] { return axis_ok(1e-10, 1e10) && axis_ok(-1e200, 1e-200); });
  in_bounded_child([] {
    Figure fig;
    fig.axes().xscale(Scale::kLog).yscale(Scale::kLog).line({1e-300, 1e300}, {1e-300, 1e300});
    std::string svg = fig.to_svg();
    return flume::plot::test::check_xml(svg).error.empty() && log_ticks(1e-300, 1e300).size() <= 12;
  });
}

TEST(HostileData, NonFinite) {
  // NaN and infinities are gaps; an axis of nothing finite falls back to [0, 1].
  in_bounded_child([] { return figure_ok({0, 1, 2, 3}, {kNaN, 1, kInf, -kInf}); });
  in_bounded_child([] { return figure_ok({kNaN, kNaN}, {kNaN, kInf}); });
  EXPECT_THROW(nice_axis(kNaN, 1), std::invalid_argument);
  EXPECT_THROW(nice_axis(0, kInf), std::invalid_argument);
}

TEST(HostileData, FixedLimitsHistogramAndColourScale) {
  // Fixed limits a few ulps apart, a histogram of one repeated huge value, a heat map of nearly equal cells.
  in_bounded_child([] {
    Figure fig;
    fig.axes().xlim(1, std::nextafter(1.0, 2.0)).line({0, 1, 2}, {0, 1e300, 2});
    fig.axes(0, 0).histogram({1e300, 1e300, 1e300}, 10);
    std::string svg = fig.to_svg();
    return flume::plot::test::check_xml(svg).error.empty() && svg.find("nan") == std::string::npos;
  });
  in_bounded_child([] {
    Figure fig;
    double v = 0.1, v1 = std::nextafter(v, 1.0);
    fig.axes().heatmap({0, 1, 2}, {0, 1}, {v, v1});
    std::string svg = fig.to_svg();
    return flume::plot::test::check_xml(svg).error.empty() && svg.find("nan") == std::string::npos &&
           nice_ticks(v, v1).size() <= 12;
  });
}

}  // namespace
