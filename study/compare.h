// How far one run's outputs are from a reference's: gauge series over a common time window, peaks, arrival
// times, scalar run metrics (debris displacements, peak forces), and the Pareto front of settings in (cost,
// error). Plain functions on plain vectors, so the tests can check them on synthetic data with a known
// answer.
#pragma once
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace flume::study {

// A sampled record: strictly increasing times, values (NaN where the instrument had no reading).
struct Series {
  std::vector<double> time, value;
};

// Linear interpolation of `s` at t; NaN outside its time span or next to a NaN sample.
double interpolate_at(const Series& s, double t);

// RMS of (sim - ref) over the reference's samples in [t0, t1] that also lie in the simulated span, the
// simulation interpolated onto the reference's times (a measured record fixes the comparison grid, so the
// error does not depend on how finely the run sampled). NaN when no sample pair is finite.
double rms_difference(const Series& sim, const Series& ref, double t0, double t1);

// Largest finite value in [t0, t1]; NaN when there is none.
double peak_in(const Series& s, double t0, double t1);

// The first time in [t0, t1] at which the value rises `threshold` above the first finite value in the window
// (the definition of solver/run_output.cpp's `<gauge>.arrival_s`); NaN when it never does.
double arrival_time(const Series& s, double threshold, double t0, double t1);

struct GaugeError {
  std::string name;
  double rms_m = 0;           // RMS of the difference over the window
  double ref_peak_m = 0;      // the reference's peak in the window
  double peak_m = 0;          // the run's
  double peak_rel = 0;        // (peak - ref_peak) / |ref_peak|
  double arrival_s = 0;       // NaN: never arrived
  double ref_arrival_s = 0;   // NaN: never arrived
  double arrival_diff_s = 0;  // arrival - ref_arrival; NaN unless both arrived
  double rms_rel = 0;         // rms_m / |ref_peak_m|: the dimensionless error the Pareto front uses
};

GaugeError compare_gauge(const std::string& name, const Series& sim, const Series& ref, double t0, double t1,
                         double arrival_threshold_m);

// One scalar of a run's run.json `metrics` object as the study read it. `present` is false where run.json
// has no such name (the solver leaves out what it could not compute, such as the arrival of a wave that never
// came); a name that is there with a value that is not a finite number (null, a string) is present with NaN.
struct MetricReading {
  bool present = false;
  double value = std::numeric_limits<double>::quiet_NaN();
};

// A metric the study compares: a run.json metric name, or (in the spec) a pattern in which `*` stands for
// any run of characters other than '.'. `scale` is the floor of the relative difference's denominator, in
// the metric's unit: a metric whose reference is near zero (a lateral displacement of a few mm, a spreading
// angle of a degree) would otherwise turn a small absolute difference into a huge relative one.
struct MetricOutput {
  std::string name;
  double scale = 0;
};

// true when `name` matches `pattern`: `*` matches any run of characters (none included) without a '.', so a
// wildcard stays inside one component of the dotted name (`D*.rest_x_m` matches D1.rest_x_m and D12.rest_x_m,
// `*.peak_force_n` every load cell, neither anything with one more component); every other character
// matches itself.
bool wildcard_match(const std::string& pattern, const std::string& name);

// The metrics a study compares, from the spec's patterns and the reference run's metric names: a pattern
// with `*` becomes the names it matches (in the order of `reference_names`); a name without `*` stays as it
// is, also where the reference lacks it (every row then reports the reference as missing); a name that two
// patterns give is kept once, with the first one's scale. The index of each pattern with `*` that matches
// nothing goes to `unmatched` (a typo the caller reports).
std::vector<MetricOutput> expand_metric_patterns(const std::vector<MetricOutput>& patterns,
                                                 const std::vector<std::string>& reference_names,
                                                 std::vector<size_t>* unmatched);

struct MetricError {
  std::string name;
  double scale = 0;
  MetricReading value, ref;
  double diff = std::numeric_limits<double>::quiet_NaN();  // value - ref
  // |value - ref| / max(|ref|, scale); NaN unless both are finite and that denominator is > 0.
  double rel = std::numeric_limits<double>::quiet_NaN();
};

MetricError compare_metric(const MetricOutput& metric, const MetricReading& value, const MetricReading& ref);

// What is wrong with a reading: "missing", "not finite", or empty for a finite value.
std::string reading_problem(const MetricReading& m);

// Why a metric error has no relative difference, in a few words: the reference's problem ("reference
// missing", "reference not finite", "reference 0, scale 0"), else the run's; empty when it has one.
std::string metric_problem(const MetricError& e);

// The reference defines a metric's relative difference: it has a finite value, and max(|ref|, scale) > 0.
bool reference_defines(const MetricError& e);

// The study's aggregate metric error: the mean of `rel` over the metrics the reference defines. NaN when
// the reference defines none, and NaN when the run lacks one of those (missing or not finite): a mean over
// fewer metrics would rank that run against the others on different terms.
double mean_metric_error(const std::vector<MetricError>& errors);

// true for each point that no other point dominates: another with cost <= and error <= and one of them
// strictly smaller. Points with a non-finite cost or error are never on the front and dominate nothing.
std::vector<bool> pareto_front(const std::vector<double>& cost, const std::vector<double>& error);

}  // namespace flume::study
