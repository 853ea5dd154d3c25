#include "report/export.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/command.h"
#include "common/errors.h"
#include "common/number_text.h"
#include "store/h5/run_file.h"

namespace flume::report {
namespace {

namespace fs = std::filesystem;

// Column suffixes of an n-column dataset: x, y, z for vectors; (x, z) in 2D (the last axis is vertical);
// w, x, y, z for quaternions; 0, 1, ... for the bins of a 3D section.
std::vector<std::string> suffixes(const std::string& dataset, std::size_t cols, int dimension) {
  if (cols == 4 && dataset == "orientation") return {"_w", "_x", "_y", "_z"};
  if (cols == 3) return {"_x", "_y", "_z"};
  if (cols == 2 && dimension == 2) return {"_x", "_z"};
  std::vector<std::string> s;
  for (std::size_t i = 0; i < cols; ++i) s.push_back("_" + std::to_string(i));
  return s;
}

// One instrument's series: the datasets beside `time` whose rows are the time samples (coordinates such as a
// section's y and z, and its velocity_profile, have other lengths and stay in result.h5).
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<double>> columns;
};

Table series_of(const h5::Reader& h5, const std::string& group, int dimension) {
  Table t;
  const std::vector<double> time = h5.read_vector(group + "/time");
  t.header.push_back("time");
  t.columns.push_back(time);
  for (const std::string& ds : h5.list(group)) {
    const std::string path = group + "/" + ds;
    if (ds == "time" || !h5.exists(path)) continue;
    std::vector<std::size_t> shape;
    try {
      shape = h5.shape(path);
    } catch (const std::runtime_error&) {
      continue;  // a group, not a dataset
    }
    if (shape.empty() || shape[0] != time.size() || shape.size() > 2) continue;
    const std::size_t cols = shape.size() == 2 ? shape[1] : 1;
    const std::vector<double> v = h5.read_vector(path);
    const std::vector<std::string> suffix = cols == 1 ? std::vector<std::string>{""} : suffixes(ds, cols, dimension);
    for (std::size_t c = 0; c < cols; ++c) {
      std::vector<double> col(time.size());
      for (std::size_t i = 0; i < time.size(); ++i) col[i] = v[i * cols + c];
      t.header.push_back(ds + suffix[c]);
      t.columns.push_back(std::move(col));
    }
  }
  return t;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

// DIR/<kind>.csv in long form: the key columns (instrument name; for debris also the rate) then the series,
// one row per instrument and time sample. Instruments with other columns than the first add theirs.
void write_kind(const h5::Reader& h5, const std::string& kind, const std::vector<std::string>& keys,
                int dimension, const std::string& file) {
  struct Part {
    std::vector<std::string> key;
    Table table;
  };
  std::vector<Part> parts;
  std::vector<std::string> names = h5.list("/" + kind);
  std::vector<std::pair<std::vector<std::string>, std::string>> groups;  // key values, group path
  for (const auto& n : names) {
    if (keys.size() == 1) {
      groups.push_back({{n}, "/" + kind + "/" + n});
    } else {
      for (const auto& r : h5.list("/" + kind + "/" + n)) groups.push_back({{n, r}, "/" + kind + "/" + n + "/" + r});
    }
  }
  std::vector<std::string> header = keys;
  for (const auto& [key, g] : groups) {
    if (!h5.exists(g + "/time")) continue;
    parts.push_back({key, series_of(h5, g, dimension)});
    for (const auto& h : parts.back().table.header)
      if (std::find(header.begin(), header.end(), h) == header.end()) header.push_back(h);
  }
  const std::string tmp = file + ".part";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(file, "", "cannot write the CSV file");
    for (std::size_t i = 0; i < header.size(); ++i) out << (i ? "," : "") << csv_field(header[i]);
    out << "\n";
    for (const Part& p : parts) {
      std::vector<int> where(header.size(), -1);
      for (std::size_t h = keys.size(); h < header.size(); ++h)
        for (std::size_t c = 0; c < p.table.header.size(); ++c)
          if (p.table.header[c] == header[h]) where[h] = static_cast<int>(c);
      const std::size_t rows = p.table.columns[0].size();
      for (std::size_t r = 0; r < rows; ++r) {
        for (std::size_t h = 0; h < header.size(); ++h) {
          if (h) out << ",";
          if (h < keys.size()) out << csv_field(p.key[h]);
          else if (where[h] >= 0) out << round_trip_text(p.table.columns[static_cast<std::size_t>(where[h])][r]);
        }
        out << "\n";
      }
    }
    if (!out) throw InputError(file, "", "cannot write the CSV file");
  }
  fs::rename(tmp, file);
}

}  // namespace

std::vector<std::string> export_run_csv(const std::string& h5_file, const std::string& out_dir) {
  std::unique_ptr<h5::Reader> h5;
  try {
    h5 = std::make_unique<h5::Reader>(h5_file);
  } catch (const std::runtime_error&) {
    throw InputError(h5_file, "", "cannot open as an HDF5 file");
  }
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir, "--csv", "cannot create the folder: " + ec.message());
  int dimension = 3;
  try {
    dimension = static_cast<int>(h5->number_attribute("/", "dimension"));
  } catch (const std::runtime_error&) {
    // written by a flume before the attribute: 3D column names
  }
  std::vector<std::string> written;
  for (const char* kind : {"gauges", "probes", "loads", "pressure_probes", "sections"}) {
    if (!h5->exists(std::string("/") + kind)) continue;
    const std::string file = (fs::path(out_dir) / (std::string(kind) + ".csv")).string();
    write_kind(*h5, kind, {"name"}, dimension, file);
    written.push_back(file);
  }
  if (h5->exists("/debris")) {
    const std::string file = (fs::path(out_dir) / "debris.csv").string();
    write_kind(*h5, "debris", {"name", "rate"}, dimension, file);
    written.push_back(file);
  }
  if (h5->exists("/diagnostics/time")) {
    const std::string file = (fs::path(out_dir) / "diagnostics.csv").string();
    const Table t = series_of(*h5, "/diagnostics", dimension);
    std::ofstream out(file + ".part");
    for (std::size_t i = 0; i < t.header.size(); ++i) out << (i ? "," : "") << t.header[i];
    out << "\n";
    for (std::size_t r = 0; r < t.columns[0].size(); ++r) {
      for (std::size_t c = 0; c < t.columns.size(); ++c) out << (c ? "," : "") << round_trip_text(t.columns[c][r]);
      out << "\n";
    }
    if (!out) throw InputError(file, "", "cannot write the CSV file");
    out.close();
    fs::rename(file + ".part", file);
    written.push_back(file);
  }
  return written;
}

void add_export_command(CLI::App& app) {
  struct Args {
    std::string run_dir, csv;
  };
  auto a = std::make_shared<Args>();
  app.add_option("RUN_DIR", a->run_dir, "a finished run's folder (the --out of `flume run`)")->required();
  app.add_option("--csv", a->csv, "the folder for gauges.csv, probes.csv, loads.csv, pressure_probes.csv, sections.csv, debris.csv, "
                                  "diagnostics.csv (long form, SI units: docs/results.md)")
      ->required();
  cli::on_parse(app, [a]() -> int {
    if (!fs::is_directory(a->run_dir))
      throw InputError(a->run_dir, "", "no such run folder (the --out folder of a `flume run`)");
    const std::string h5 = (fs::path(a->run_dir) / "result.h5").string();
    if (!fs::exists(h5)) throw InputError(h5, "", "missing: the run did not finish");
    for (const std::string& f : export_run_csv(h5, a->csv)) std::printf("wrote %s\n", f.c_str());
    return kExitOk;
  });
}

}  // namespace flume::report
