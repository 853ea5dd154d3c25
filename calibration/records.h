// Gauge records: the targets a calibration fits (CSV, checked line by line before any run), the simulated
// ones it reads back from a run's result.h5, and the CSV it writes for a twin experiment.
//
// Target CSV: `#` lines and blank lines are skipped; the first other line is the header. Column 1 is time
// (`t`, `time` or `time_s`, optionally with a unit: `time [s]`, `t [ms]`); every other column is a gauge's
// elevation above still water, named by its header, optionally with a unit: `WG1`, `WG1 [m]`, `WG1 [mm]`,
// `WG1 [cm]` (no unit: metres). Times must increase strictly; every cell must be a finite decimal number.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace flume::calibration {

struct TargetRecord {
  std::string gauge;
  std::string file;    // for messages
  std::string column;  // header text of its column
  double weight = 1.0;
  std::vector<double> time, elevation;  // SI (s, m)
};

// Reads one CSV. `gauge_columns` (gauge -> column name, the header text with or without its unit) picks the
// columns; empty: every elevation column, named after its gauge. `gauges`: the scene's gauges. The window
// [t0, t1] must lie within the record's time span. Throws InputError(file, "line L, column C (name)", ...).
std::vector<TargetRecord> read_target_csv(
    const std::string& file, const std::vector<std::pair<std::string, std::string>>& gauge_columns,
    const std::vector<std::string>& gauges, double window_start_s, double window_end_s, double weight,
    const std::string& spec_field);
// The same on the file's text (`file` names it in messages).
std::vector<TargetRecord> parse_target_csv(
    const std::string& text, const std::string& file,
    const std::vector<std::pair<std::string, std::string>>& gauge_columns, const std::vector<std::string>& gauges,
    double window_start_s, double window_end_s, double weight, const std::string& spec_field);
// A target file's text, bounded before it is read (a regular file of at most kMaxTargetBytes).
inline constexpr std::size_t kMaxTargetBytes = std::size_t{64} << 20;
inline constexpr std::size_t kMaxTargetColumns = 1000;
std::string read_target_text(const std::string& file, const std::string& spec_field);

struct SimRecord {
  std::vector<double> time, elevation;
};
// /gauges/<name>/{time, elevation} of a result file. Throws std::runtime_error naming what is missing.
SimRecord read_sim_gauge(const std::string& h5_file, const std::string& gauge);

// Writes "time_s,<gauge> [m],..." from records on a common time axis (the first record's) and returns the
// RMS of the noise added: Gaussian, sigma `noise_m`, from a 64-bit Mersenne Twister seeded with `seed`
// (Box-Muller written out, so the same seed gives the same file with any standard library).
double write_target_csv(const std::string& file, const std::vector<std::string>& gauges,
                        const std::vector<SimRecord>& records, double noise_m, std::uint64_t seed,
                        double from_s, double to_s);

// Linear interpolation of (time, value) at t, holding the end values outside the span.
double interpolate(const std::vector<double>& time, const std::vector<double>& value, double t);

}  // namespace flume::calibration
