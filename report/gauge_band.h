// The spread of one gauge over many runs (the posterior draws of a calibration, the members of a campaign):
// at each time of the first record, the quantiles of every record there (linear interpolation in time; a
// record that does not cover the time is left out of it), for `flume gauges --band`.
#pragma once
#include <vector>

namespace flume::report {

struct TimeSeries {
  std::vector<double> time, value;
};

struct GaugeBand {
  std::vector<double> time, lo, median, hi;  // NaN where no record covers the time
};

// Quantile p of `values` (sorted in place): linear between order statistics, the sample quantile of type 7
// in Hyndman & Fan (1996), as numpy and R give by default. NaN for none.
double sample_quantile(std::vector<double>& values, double p);

// The band holding `level` (in (0, 1)) of the records at each time, between the (1 - level) / 2 and
// (1 + level) / 2 quantiles; with n records the outer quantiles need n >= 2 / (1 - level) to differ from the
// extremes (40 for 95 %).
GaugeBand gauge_band(const std::vector<TimeSeries>& records, double level);

}  // namespace flume::report
