// Target CSV checking, result.h5 gauge reading, twin-experiment target writing.
#include "calibration/records.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>

#include "common/errors.h"
#include "common/input/json_input.h"
#include "store/h5/run_file.h"

namespace flume::calibration {
namespace {

// |eta| above this in a record read as metres is a unit mistake: the flume is 1 m deep.
constexpr double kMaxElevation_m = 2.0;

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const auto b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

// "WG1 [mm]" -> ("WG1", "mm"); "WG1" -> ("WG1", "").
std::pair<std::string, std::string> name_and_unit(const std::string& header) {
  const std::string h = trim(header);
  if (!h.empty() && (h.back() == ']' || h.back() == ')')) {
    const char open = h.back() == ']' ? '[' : '(';
    const auto p = h.rfind(open);
    if (p != std::string::npos) return {trim(h.substr(0, p)), trim(h.substr(p + 1, h.size() - p - 2))};
  }
  return {h, ""};
}

bool parse_number(const std::string& cell, double& out) {
  if (cell.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtod(cell.c_str(), &end);
  return end == cell.c_str() + cell.size() && errno != ERANGE && std::isfinite(out);
}

}  // namespace

double interpolate(const std::vector<double>& time, const std::vector<double>& value, double t) {
  if (time.empty()) return std::nan("");
  if (t <= time.front()) return value.front();
  if (t >= time.back()) return value.back();
  const auto it = std::upper_bound(time.begin(), time.end(), t);
  const size_t k = static_cast<size_t>(it - time.begin());
  const double w = (t - time[k - 1]) / (time[k] - time[k - 1]);
  return value[k - 1] + w * (value[k] - value[k - 1]);
}

std::vector<TargetRecord> read_target_csv(
    const std::string& file, const std::vector<std::pair<std::string, std::string>>& gauge_columns,
    const std::vector<std::string>& gauges, double window_start_s, double window_end_s, double weight,
    const std::string& spec_field) {
  return parse_target_csv(read_target_text(file, spec_field), file, gauge_columns, gauges, window_start_s,
                          window_end_s, weight, spec_field);
}

std::string read_target_text(const std::string& file, const std::string& spec_field) {
  return input::read_input_file(file, kMaxTargetBytes, "target record (" + spec_field + ")");
}

std::vector<TargetRecord> parse_target_csv(
    const std::string& text, const std::string& file,
    const std::vector<std::pair<std::string, std::string>>& gauge_columns, const std::vector<std::string>& gauges,
    double window_start_s, double window_end_s, double weight, const std::string& spec_field) {
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  std::vector<std::string> header;
  int header_line = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    header = split(t);
    header_line = line_no;
    break;
  }
  if (header.empty()) throw InputError(file, "", "is empty: expected a header line such as 'time_s,WG1'");
  auto where = [&](int l, size_t c) {
    return "line " + std::to_string(l) + ", column " + std::to_string(c + 1) + " (" + header[c] + ")";
  };
  if (header.size() < 2)
    throw InputError(file, "line " + std::to_string(header_line),
                     "the header has one column; expected time then one column per gauge, e.g. 'time_s,WG1'");
  if (header.size() > kMaxTargetColumns)
    throw InputError(file, "line " + std::to_string(header_line),
                     "the header has " + std::to_string(header.size()) + " columns (allowed: at most " +
                         std::to_string(kMaxTargetColumns) + ")");

  // Units: time in s or ms, elevation in m, cm or mm; the scale to SI of each column.
  std::vector<double> scale(header.size(), 1.0);
  std::vector<std::string> names(header.size());
  {
    auto [name, unit] = name_and_unit(header[0]);
    if (name != "t" && name != "time" && name != "time_s")
      throw InputError(file, where(header_line, 0),
                       "the first column must be time, named t, time or time_s (got '" + header[0] + "')");
    if (unit == "ms")
      scale[0] = 1e-3;
    else if (!unit.empty() && unit != "s")
      throw InputError(file, where(header_line, 0), "time unit must be s or ms (got '" + unit + "')");
    names[0] = name;
  }
  for (size_t c = 1; c < header.size(); ++c) {
    auto [name, unit] = name_and_unit(header[c]);
    static const std::map<std::string, double> units = {{"", 1.0}, {"m", 1.0}, {"cm", 1e-2}, {"mm", 1e-3}};
    auto u = units.find(unit);
    if (u == units.end())
      throw InputError(file, where(header_line, c),
                       "elevation unit must be m, cm or mm (got '" + unit + "')");
    if (name.empty()) throw InputError(file, where(header_line, c), "the column has no name");
    for (size_t k = 1; k < c; ++k)
      if (names[k] == name)
        throw InputError(file, where(header_line, c), "repeats the column name '" + name + "'");
    scale[c] = u->second;
    names[c] = name;
  }

  // Which columns are which gauges.
  std::vector<std::pair<std::string, size_t>> picked;  // gauge -> column
  auto known = [&](const std::string& g) {
    return std::find(gauges.begin(), gauges.end(), g) != gauges.end();
  };
  std::string gauge_list;
  for (const auto& g : gauges) gauge_list += (gauge_list.empty() ? "" : ", ") + g;
  if (gauge_columns.empty()) {
    for (size_t c = 1; c < header.size(); ++c) {
      if (!known(names[c]))
        throw InputError(file, where(header_line, c),
                         "'" + names[c] + "' is not a gauge of the scene (its gauges: " + gauge_list +
                             "); rename the column or map it with " + spec_field + ".gauges");
      picked.emplace_back(names[c], c);
    }
  } else {
    for (const auto& [gauge, column] : gauge_columns) {
      size_t found = 0;
      if (column.empty()) {  // `gauge`: the file's one elevation column, whatever its name
        if (header.size() != 2)
          throw InputError(file, "line " + std::to_string(header_line),
                           "has " + std::to_string(header.size() - 1) +
                               " elevation columns; say which is gauge " + gauge + " with " + spec_field +
                               ".gauges: {\"" + gauge + "\": \"<column>\"}");
        picked.emplace_back(gauge, 1);
        continue;
      }
      for (size_t c = 1; c < header.size(); ++c)
        if (header[c] == column || names[c] == column) found = c;
      if (!found) {
        std::string cols;
        for (size_t c = 1; c < header.size(); ++c) cols += (cols.empty() ? "" : ", ") + header[c];
        throw InputError(file, "line " + std::to_string(header_line),
                         "has no column '" + column + "' (mapped to gauge " + gauge + " by " + spec_field +
                             ".gauges); its columns: " + cols);
      }
      picked.emplace_back(gauge, found);
    }
  }

  std::vector<std::vector<double>> cols(header.size());
  int prev_line = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const auto cells = split(t);
    if (cells.size() != header.size())
      throw InputError(file, "line " + std::to_string(line_no),
                       "has " + std::to_string(cells.size()) + " cells but the header has " +
                           std::to_string(header.size()) + " columns (a missing or extra cell)");
    for (size_t c = 0; c < cells.size(); ++c) {
      double v = 0;
      if (!parse_number(cells[c], v))
        throw InputError(file, where(line_no, c),
                         cells[c].empty() ? "is empty; every cell must be a finite decimal number"
                                          : "'" + cells[c] + "' is not a finite decimal number");
      v *= scale[c];
      if (c == 0 && !cols[0].empty() && !(v > cols[0].back()))
        throw InputError(file, where(line_no, c),
                         v == cols[0].back()
                             ? "repeats the time " + fmt(v) + " s of line " + std::to_string(prev_line) +
                                   "; times must increase strictly"
                             : "time " + fmt(v) + " s is before " + fmt(cols[0].back()) + " s on line " +
                                   std::to_string(prev_line) + "; times must be sorted, increasing strictly");
      if (c > 0 && std::fabs(v) > kMaxElevation_m)
        throw InputError(file, where(line_no, c),
                         "elevation " + fmt(v) + " m is beyond +-" + fmt(kMaxElevation_m) +
                             " m, impossible in the flume: is the column in mm or cm? Say so in its header, "
                             "e.g. '" +
                             names[c] + " [mm]'");
      cols[c].push_back(v);
    }
    prev_line = line_no;
  }
  if (cols[0].size() < 2) throw InputError(file, "", "has fewer than two data lines");
  const double t0 = cols[0].front(), t1 = cols[0].back();
  if (t0 > window_start_s || t1 < window_end_s)
    throw InputError(file, "",
                     "its time span [" + fmt(t0) + ", " + fmt(t1) + "] s does not cover objective.window [" +
                         fmt(window_start_s) + ", " + fmt(window_end_s) + "] s");
  const auto in_window = std::count_if(cols[0].begin(), cols[0].end(),
                                       [&](double t) { return t >= window_start_s && t <= window_end_s; });
  if (in_window < 2)
    throw InputError(file, "",
                     "has " + std::to_string(in_window) + " sample(s) in objective.window [" +
                         fmt(window_start_s) + ", " + fmt(window_end_s) + "] s; at least 2 are needed");

  std::vector<TargetRecord> out;
  for (const auto& [gauge, c] : picked) {
    TargetRecord r;
    r.gauge = gauge;
    r.file = file;
    r.column = header[c];
    r.weight = weight;
    r.time = cols[0];
    r.elevation = cols[c];
    out.push_back(std::move(r));
  }
  return out;
}

SimRecord read_sim_gauge(const std::string& h5_file, const std::string& gauge) {
  h5::Reader reader(h5_file);
  const std::string g = "/gauges/" + gauge;
  if (!reader.exists(g + "/time") || !reader.exists(g + "/elevation"))
    throw std::runtime_error(h5_file + " has no " + g + "/time and " + g + "/elevation");
  SimRecord r;
  r.time = reader.read_vector(g + "/time");
  r.elevation = reader.read_vector(g + "/elevation");
  if (r.time.size() != r.elevation.size() || r.time.empty())
    throw std::runtime_error(h5_file + ": " + g + " has " + std::to_string(r.time.size()) + " times and " +
                             std::to_string(r.elevation.size()) + " elevations");
  for (size_t k = 1; k < r.time.size(); ++k)
    if (!(r.time[k] > r.time[k - 1]))
      throw std::runtime_error(h5_file + ": " + g + "/time does not increase");
  return r;
}

double write_target_csv(const std::string& file, const std::vector<std::string>& gauges,
                        const std::vector<SimRecord>& records, double noise_m, std::uint64_t seed,
                        double from_s, double to_s) {
  if (records.empty() || records.size() != gauges.size()) throw std::invalid_argument("one record per gauge");
  std::mt19937_64 rng(seed);
  auto uniform = [&] { return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53; };  // in (0, 1)
  auto gaussian = [&] {                                                                 // Box & Muller 1958
    const double u1 = uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  };
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file + ": cannot write");
  out << "time_s";
  for (const auto& g : gauges) out << "," << g << " [m]";
  out << "\n";
  out.precision(17);
  double sum2 = 0;
  size_t n = 0;
  for (double t : records[0].time) {
    if (t < from_s - 1e-12 || t > to_s + 1e-12) continue;
    out << t;
    for (const auto& r : records) {
      const double e = noise_m > 0 ? noise_m * gaussian() : 0.0;
      sum2 += e * e;
      ++n;
      out << "," << interpolate(r.time, r.elevation, t) + e;
    }
    out << "\n";
  }
  if (!out) throw std::runtime_error(file + ": cannot write");
  return n ? std::sqrt(sum2 / n) : 0.0;
}

}  // namespace flume::calibration
