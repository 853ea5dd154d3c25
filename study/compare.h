// How far one run's outputs are from a reference's: gauge series over a common time window, peaks, arrival
// times, and the Pareto front of settings in (cost, error). Plain functions on plain vectors, so the tests
// can check them on synthetic series with a known answer.
#pragma once
#include <cstddef>
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

// true for each point that no other point dominates: another with cost <= and error <= and one of them
// strictly smaller. Points with a non-finite cost or error are never on the front and dominate nothing.
std::vector<bool> pareto_front(const std::vector<double>& cost, const std::vector<double>& error);

}  // namespace flume::study
