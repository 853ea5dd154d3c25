// `flume gauges RUN_DIR[=LABEL] ... --out FILE.svg`: the free-surface gauge (and pressure probe) records of one
// or more finished runs, one panel per gauge (stacked, sharing the time axis) with one line per run, and on stdout one line per
// gauge and run with the peak, its time and the arrival, so that docs can quote the numbers.
#include "report/gauges.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/command.h"
#include "common/errors.h"
#include "common/plot/figure.h"
#include "common/gauge_summary.h"
#include "report/gauge_band.h"
#include "store/h5/run_file.h"

namespace flume::report {
namespace {

namespace fs = std::filesystem;

constexpr double kArrivalThresholdM = 0.005;  // 5 mm, as `flume run` has it for run.json's arrival_s

struct Record {
  std::vector<double> time, value;
  std::string unit = "m";
  bool pressure = false;  // a pressure probe's record (Pa), not a gauge's
};

struct Run {
  std::string dir, label, h5_file;
  std::vector<std::string> gauges;  // natural order
  std::map<std::string, Record> records;
};

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// "DIR=LABEL" (split at the last '=', unless the whole argument is an existing path); the label defaults to
// the folder's name.
std::pair<std::string, std::string> parse_run_arg(const std::string& a) {
  std::string dir = a, label;
  const std::size_t eq = a.rfind('=');
  if (eq != std::string::npos && !fs::exists(a)) {
    dir = a.substr(0, eq);
    label = a.substr(eq + 1);
    if (dir.empty()) throw cli::UsageError(a, "RUN_DIR=LABEL needs a run folder before '='");
    if (label.empty()) throw cli::UsageError(a, "RUN_DIR=LABEL needs a label after '='");
  }
  if (label.empty()) {
    fs::path p = fs::absolute(fs::path(dir)).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();
    label = p.filename().string();
    if (label.empty()) label = dir;
  }
  return {dir, label};
}

std::vector<std::string> parse_gauge_list(const std::string& option, const std::string& value) {
  std::vector<std::string> names;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = value.find(',', start);
    const std::string name = value.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (name.empty()) throw cli::UsageError(option, "'" + value + "': a comma-separated list of gauge names, none empty");
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return names;
}

double parse_positive(const std::string& option, const std::string& value) {
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || end != value.c_str() + value.size() || !std::isfinite(v) || v <= 0)
    throw cli::UsageError(option, "'" + value + "': a positive number of seconds");
  return v;
}

// An optional string attribute `unit` on the elevation dataset or the gauge's group; "m" without one.
std::string gauge_unit(const h5::Reader& h5, const std::string& gauge_group) {
  for (const std::string& where : {gauge_group + "/elevation", gauge_group}) {
    try {
      const std::string u = h5.string_attribute(where, "unit");
      if (!u.empty()) return u;
    } catch (const std::runtime_error&) {
      // no such attribute
    }
  }
  return "m";
}

Run open_run(const std::string& dir, const std::string& label) {
  Run r;
  r.dir = dir;
  r.label = label;
  r.h5_file = (fs::path(dir) / "result.h5").string();
  if (!fs::is_directory(dir)) throw InputError(dir, "", "no such run folder (the --out folder of a `flume run`)");
  if (!fs::exists(r.h5_file)) throw InputError(r.h5_file, "", "missing: the run did not finish");
  return r;
}

// The gauges' elevations and the pressure probes' pressures (issue 30) of a run, over t <= t_max: those
// named in `wanted`, or all of them (gauges first). A run needs one or the other.
void read_gauges(Run& r, const std::vector<std::string>* wanted, double t_max) {
  std::unique_ptr<h5::Reader> h5;
  try {
    h5 = std::make_unique<h5::Reader>(r.h5_file);
  } catch (const std::runtime_error&) {
    throw InputError(r.h5_file, "", "cannot open as an HDF5 file");
  }
  std::vector<std::string> probes;
  if (h5->exists("/gauges")) r.gauges = h5->list("/gauges");
  if (h5->exists("/pressure_probes")) probes = h5->list("/pressure_probes");
  if (r.gauges.empty() && probes.empty())
    throw InputError(r.h5_file, "/gauges", "missing: the run recorded no gauges (nor pressure probes)");
  sort_gauge_names(r.gauges);
  sort_gauge_names(probes);
  std::vector<std::string> all = r.gauges;
  all.insert(all.end(), probes.begin(), probes.end());
  r.gauges = all;
  const std::vector<std::string>& names = wanted ? *wanted : r.gauges;
  for (const std::string& name : names) {
    const bool is_probe = std::find(probes.begin(), probes.end(), name) != probes.end();
    const std::string group = (is_probe ? "/pressure_probes/" : "/gauges/") + name;
    const char* value_name = is_probe ? "pressure" : "elevation";
    if (std::find(r.gauges.begin(), r.gauges.end(), name) == r.gauges.end())
      throw InputError(r.h5_file, group, "missing: the run has gauges and pressure probes " + join(r.gauges));
    Record rec;
    for (const char* ds : {"time", value_name})
      if (!h5->exists(group + "/" + ds)) throw InputError(r.h5_file, group + "/" + ds, "missing");
    const std::vector<double> t = h5->read_vector(group + "/time"), v = h5->read_vector(group + "/" + value_name);
    if (t.size() != v.size())
      throw InputError(r.h5_file, group, "time has " + std::to_string(t.size()) + " samples, " + value_name + " " +
                                             std::to_string(v.size()) + ": they must match");
    for (std::size_t i = 0; i < t.size(); ++i)
      if (t[i] <= t_max) {
        rec.time.push_back(t[i]);
        rec.value.push_back(v[i]);
      }
    if (rec.time.empty())
      throw InputError(r.h5_file, group + "/time",
                       t.empty() ? "is empty" : "has no sample at or before --t-max " + std::to_string(t_max) + " s");
    rec.unit = is_probe ? "Pa" : gauge_unit(*h5, group);
    rec.pressure = is_probe;
    r.records[name] = std::move(rec);
  }
}

// 5 mm in the record's unit; 0 (no arrival) for a unit that is not a length in m, cm or mm.
double arrival_threshold(const std::string& unit) {
  if (unit == "m") return kArrivalThresholdM;
  if (unit == "cm") return kArrivalThresholdM * 100;
  if (unit == "mm") return kArrivalThresholdM * 1000;
  return 0;
}

void print_summary(const std::string& gauge, const Run& r) {
  const Record& rec = r.records.at(gauge);
  if (rec.pressure) {  // the metrics `flume run` puts in run.json (summarize_pressure)
    const PressureSummary p = summarize_pressure(rec.time, rec.value);
    std::printf("%s %s: peak %.1f Pa at %.4f s, impulse %.3f Pa s\n", gauge.c_str(), r.label.c_str(), p.peak + 0.0,
                p.peak_time, p.impulse + 0.0);
    return;
  }
  const double threshold = arrival_threshold(rec.unit);
  const GaugeSummary s = summarize_gauge(rec.time, rec.value, threshold > 0 ? threshold : 0);
  std::printf("%s %s: ", gauge.c_str(), r.label.c_str());
  if (s.has_peak)
    std::printf("peak %.4f %s at %.3f s", s.peak + 0.0, rec.unit.c_str(), s.peak_time);  // + 0.0: no "-0.0000"
  else
    std::printf("peak none (no finite sample)");
  if (threshold <= 0)
    std::printf(", arrival n/a (unit %s)\n", rec.unit.c_str());
  else if (s.arrived)
    std::printf(", arrival %.3f s (5 mm above the first reading, %.4f %s)\n", s.arrival_time, s.first + 0.0,
                rec.unit.c_str());
  else
    std::printf(", arrival none (never 5 mm above the first reading, %.4f %s)\n", s.first + 0.0, rec.unit.c_str());
}

// One line per gauge for the band's runs: the median and the band's quantiles of their peaks and arrivals.
void print_band_summary(const std::string& gauge, const std::vector<Run>& runs, double level) {
  const Record& first = runs[0].records.at(gauge);
  if (first.pressure) return;
  const double threshold = arrival_threshold(first.unit);
  std::vector<double> peaks, arrivals;
  for (const Run& r : runs) {
    const Record& rec = r.records.at(gauge);
    const GaugeSummary s = summarize_gauge(rec.time, rec.value, threshold > 0 ? threshold : 0);
    if (s.has_peak) peaks.push_back(s.peak);
    if (threshold > 0 && s.arrived) arrivals.push_back(s.arrival_time);
  }
  const double a = (1 - level) / 2;
  std::printf("%s band of %zu runs: peak median %.4f [%.4f, %.4f] %s", gauge.c_str(), runs.size(),
              sample_quantile(peaks, 0.5), sample_quantile(peaks, a), sample_quantile(peaks, 1 - a),
              first.unit.c_str());
  if (threshold > 0)
    std::printf(", arrival in %zu: median %.3f [%.3f, %.3f] s", arrivals.size(), sample_quantile(arrivals, 0.5),
                sample_quantile(arrivals, a), sample_quantile(arrivals, 1 - a));
  std::printf(" (%g %% of the runs between the brackets)\n", 100 * level);
}

}  // namespace

void sort_gauge_names(std::vector<std::string>& names) {
  // Runs of digits compare by value, the rest character by character; ties (WG01, WG1) by plain order.
  auto natural_less = [](const std::string& a, const std::string& b) {
    std::size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
      const bool da = std::isdigit(static_cast<unsigned char>(a[i])), db = std::isdigit(static_cast<unsigned char>(b[j]));
      if (da && db) {
        std::size_t ie = i, je = j;
        while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
        while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
        std::size_t is = i, js = j;  // skip leading zeros
        while (is + 1 < ie && a[is] == '0') ++is;
        while (js + 1 < je && b[js] == '0') ++js;
        if (ie - is != je - js) return ie - is < je - js;
        const int c = a.compare(is, ie - is, b, js, je - js);
        if (c != 0) return c < 0;
        i = ie;
        j = je;
      } else {
        if (a[i] != b[j]) return a[i] < b[j];
        ++i;
        ++j;
      }
    }
    if ((i < a.size()) != (j < b.size())) return j < b.size();
    return a < b;
  };
  std::sort(names.begin(), names.end(), natural_less);
}

void add_gauges_command(CLI::App& app) {
  struct Args {
    std::vector<std::string> runs, lines;
    std::string out, title, gauges, t_max;
    bool band = false;
  };
  auto a = std::make_shared<Args>();
  app.footer(
      "One panel per gauge (default: every gauge of the first run), one line per run (LABEL: default the folder's\n"
      "name); prints per gauge and run the peak, its time and the arrival (the first time the record rises 5 mm\n"
      "above its first reading), over t <= --t-max when given. Pressure probes get panels too (after the gauges),\n"
      "with their peak pressure, its time and the pressure impulse.\n"
      "--band draws the runs as one band instead (95 % of them at each time, between the 2.5 and 97.5 %\n"
      "quantiles, and their median; with under 40 runs the band is near their extremes), for the predictive runs\n"
      "of a calibration's posterior (flume surrogate posterior --draws) or a campaign's members; --line adds\n"
      "single runs on top of it (the calibration's optimum, a reference run).");
  app.add_option("RUN_DIR", a->runs, "a finished run's folder, optionally =LABEL")->required()->type_name("RUN_DIR[=LABEL]");
  app.add_option("--out", a->out, "the .svg file to write")->required();
  app.add_option("--gauges", a->gauges, "the gauges and pressure probes to show, e.g. WG1,WG2")->type_name("WG1,WG2,...");
  app.add_option("--t-max", a->t_max, "the last time shown and summarised (s)")->type_name("S");
  app.add_option("--title", a->title, "the figure's title");
  app.add_flag("--band", a->band, "the runs as one band (95 % at each time) and their median");
  app.add_option("--line", a->lines, "with --band: a run drawn as a line on top (repeatable)")->type_name("RUN_DIR[=LABEL]");
  cli::on_parse(app, [a]() -> int {
    std::vector<std::pair<std::string, std::string>> run_args;  // dir, label
    for (const auto& r : a->runs) run_args.push_back(parse_run_arg(r));
    const std::string& out = a->out;
    const std::string& title = a->title;
    const bool have_wanted = !a->gauges.empty();
    std::vector<std::string> wanted = have_wanted ? parse_gauge_list("--gauges", a->gauges) : std::vector<std::string>{};
    const double t_max = a->t_max.empty() ? std::numeric_limits<double>::infinity() : parse_positive("--t-max", a->t_max);

    if (!a->band && !a->lines.empty()) throw cli::UsageError("--line", "goes with --band (without it every run is a line)");
    if (a->band && run_args.size() < 2) throw cli::UsageError("--band", "needs at least 2 runs to spread");
    constexpr double kBandLevel = 0.95;
    const std::size_t n_band = a->band ? run_args.size() : 0;
    for (const auto& l : a->lines) run_args.push_back(parse_run_arg(l));
    std::vector<Run> runs;
    for (const auto& [dir, label] : run_args) runs.push_back(open_run(dir, label));
    // The first run decides the default gauges; every run must have each of them.
    read_gauges(runs[0], have_wanted ? &wanted : nullptr, t_max);
    if (!have_wanted) wanted = runs[0].gauges;
    for (std::size_t k = 1; k < runs.size(); ++k) {
      read_gauges(runs[k], &wanted, t_max);
      for (const std::string& name : wanted)
        if (runs[k].records.at(name).unit != runs[0].records.at(name).unit)
          throw InputError(runs[k].h5_file, "/gauges/" + name,
                           "unit '" + runs[k].records.at(name).unit + "', but " + runs[0].h5_file + " has '" +
                               runs[0].records.at(name).unit + "': one panel needs one unit");
    }

    double t_lo = std::numeric_limits<double>::infinity(), t_hi = -t_lo;
    for (const Run& r : runs)
      for (const auto& [name, rec] : r.records)
        for (double t : rec.time)
          if (std::isfinite(t)) {
            t_lo = std::min(t_lo, t);
            t_hi = std::max(t_hi, t);
          }
    if (std::isfinite(t_max) && t_hi < t_max) t_hi = t_max;
    if (!(t_hi > t_lo)) t_hi = t_lo + 1;

    const int n = static_cast<int>(wanted.size());
    plot::Figure fig(n, 1, 1000, 80 + 260 * n);
    if (!title.empty()) fig.title(title);
    for (int g = 0; g < n; ++g) {
      const std::string& name = wanted[static_cast<std::size_t>(g)];
      plot::Axes& ax = fig.axes(g, 0);
      const Record& first = runs[0].records.at(name);
      ax.title(name).ylabel((first.pressure ? "p (" : "eta (") + first.unit + ")").xlim(t_lo, t_hi);
      if (g == n - 1) ax.xlabel("t (s)");
      if (n_band > 0) {
        std::vector<TimeSeries> records;
        for (std::size_t k = 0; k < n_band; ++k)
          records.push_back({runs[k].records.at(name).time, runs[k].records.at(name).value});
        const GaugeBand b = gauge_band(records, kBandLevel);
        const std::string band_label = "95 % of " + std::to_string(n_band) + " runs";
        ax.band(b.time, b.lo, b.hi, {.color = plot::palette(0), .label = g == 0 ? band_label : ""});
        ax.line(b.time, b.median, {.color = plot::palette(0), .width = 1.5, .label = g == 0 ? "median" : ""});
      }
      for (std::size_t k = n_band; k < runs.size(); ++k) {
        const Record& rec = runs[k].records.at(name);
        // The same colour for a run in every panel (the band has the first); dashed once the palette's eight
        // colours are used up.
        const std::size_t c = k - n_band + (n_band > 0 ? 1 : 0);
        ax.line(rec.time, rec.value,
                {.color = plot::palette(c), .width = 1.5, .dash = c < 8 ? plot::Dash::kSolid : plot::Dash::kDashed,
                 .label = g == 0 ? runs[k].label : ""});
      }
      if (g == 0) ax.legend(plot::Legend::kUpperLeft);  // before the arrival the records are flat
    }
    for (const std::string& name : wanted) {
      if (n_band > 0) print_band_summary(name, {runs.begin(), runs.begin() + static_cast<long>(n_band)}, kBandLevel);
      for (std::size_t k = n_band; k < runs.size(); ++k) print_summary(name, runs[k]);
    }
    fig.save(out);
    std::printf("wrote %s\n", out.c_str());
    return kExitOk;
  });
}

}  // namespace flume::report
