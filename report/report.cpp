// Statistics of a campaign for the report, and the files it writes besides the HTML.
#include "report/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "common/command.h"
#include "common/errors.h"

namespace flume::report {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

const char* const kCli = "command line";  // the "file" of a bad option in InputError

bool per_debris(const std::string& name) {
  static const std::regex re(R"(^D[0-9]+\..*)");
  return std::regex_match(name, re);
}

std::string num(double v) {
  if (!std::isfinite(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

json jnum(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
json jest(const Estimate& e) { return {{"value", jnum(e.value)}, {"ci", {jnum(e.ci.lo), jnum(e.ci.hi)}}}; }

std::string csv(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
  if (!out) throw std::runtime_error(p.string() + ": cannot write");
}

}  // namespace

Report build_report(const ReportOptions& options) {
  Report r;
  r.options = options;
  r.data = load_campaign(options.db_file, options.campaign);
  CampaignData& d = r.data;

  // Debris summaries join each ok run's metrics, so they get statistics, sensitivity and convergence too.
  std::set<std::string> names(d.metric_names.begin(), d.metric_names.end());
  for (auto& row : d.rows) {
    if (!row.ok()) continue;
    const auto debris = debris_of(row.metrics);
    if (debris.empty()) continue;
    for (const auto& [name, v] : derived_debris_metrics(debris, apron_geometry(d, &row).quay_x_m)) {
      row.metrics[name] = v;
      names.insert(name);
    }
  }

  for (const auto& [metric, values] : options.thresholds)
    if (!names.count(metric)) {
      std::string known;
      for (const auto& n : names)
        if (!per_debris(n)) known += (known.empty() ? "" : ", ") + n;
      throw InputError(kCli, "--thresholds",
                       "no metric named '" + metric + "' in campaign " + d.record.name +
                           " (its metrics: " + (known.empty() ? "none" : known) + ")");
    }
  for (const auto& [metric, w] : options.ci_widths)
    if (!names.count(metric))
      throw InputError(kCli, "--ci-width", "no metric named '" + metric + "' in campaign " + d.record.name);

  // Runs: each distinct run once (a repeated design point shares its run).
  std::set<std::int64_t> seen;
  for (std::size_t i = 0; i < d.rows.size(); ++i) {
    if (!seen.insert(d.rows[i].run_id).second) continue;
    ++r.counts[d.rows[i].status];
    if (!d.rows[i].ok()) r.not_ok.push_back(i);
  }

  // The distribution sample: independent draws of the inputs. In a Saltelli design these are the A and B
  // blocks; the other blocks reuse their columns and would make the runs dependent.
  const std::size_t n_rows = d.rows.size();
  if (d.is_saltelli()) {
    const std::size_t ab = std::min(n_rows, 2 * d.saltelli_base_size);
    for (std::size_t i = 0; i < ab; ++i) r.sample.push_back(i);
    r.sample_note = "the A and B blocks of the Saltelli design (" + std::to_string(ab) + " of " +
                    std::to_string(n_rows) + " design points), which are independent draws of the inputs";
  } else if (d.design_samples > 0 && n_rows > d.design_samples) {
    // An adaptive campaign: the added points cluster where the surrogate was unsure (near a threshold, say),
    // so with them the runs' statistics would be biased; the surrogate's estimates use every run.
    for (std::size_t i = 0; i < d.design_samples; ++i) r.sample.push_back(i);
    r.sample_note = "the first " + std::to_string(d.design_samples) + " of " + std::to_string(n_rows) +
                    " design points, the " + d.design_type +
                    " design's own; the other " + std::to_string(n_rows - d.design_samples) +
                    " were added by 'flume surrogate adapt' where its surrogate was least sure, not drawn "
                    "from the input law, so they enter the surrogates (section Surrogates) but not these "
                    "statistics";
  } else {
    for (std::size_t i = 0; i < n_rows; ++i) r.sample.push_back(i);
    r.sample_note = "all " + std::to_string(n_rows) + " design points of the " + d.design_type + " design";
    if (d.design_type == "grid" || d.design_type == "one_at_a_time")
      r.sample_note +=
          " (not a random sample: the intervals treat the runs as independent draws, which they are not)";
    else if (d.design_type == "lhs" || d.design_type == "sobol")
      r.sample_note +=
          " (intervals computed as for independent draws, which is conservative for this design)";
  }
  for (std::size_t i : r.sample) r.sample_ok += d.rows[i].ok();

  // Inputs for sensitivity: every parameter; a text parameter is coded by the order its values appear.
  std::vector<std::vector<double>> inputs(n_rows, std::vector<double>(d.parameters.size()));
  for (std::size_t j = 0; j < d.parameters.size(); ++j) {
    r.sensitivity_inputs.push_back(d.parameters[j].path);
    std::map<std::string, double> codes;
    for (std::size_t i = 0; i < n_rows; ++i) {
      const auto& v = d.rows[i].params[j];
      inputs[i][j] =
          v.is_text ? codes.emplace(v.text, static_cast<double>(codes.size())).first->second : v.number;
    }
  }

  const double nan = std::nan("");
  for (const auto& name : names) {
    MetricReport m;
    m.name = name;
    m.headline = !per_debris(name);
    for (std::size_t i : r.sample) {
      const auto& row = d.rows[i];
      if (!row.ok()) continue;
      auto it = row.metrics.find(name);
      if (it == row.metrics.end()) {
        ++m.missing;
      } else {
        m.values.push_back(it->second);
      }
    }
    std::vector<double> th;
    if (auto it = options.thresholds.find(name); it != options.thresholds.end()) th = it->second;
    if (m.values.size() >= 2) {
      StatsOptions so = options.stats;
      m.summary = summarize(m.values, th, so);
      if (m.headline) {
        m.ecdf = ecdf_band(m.values, so);
        m.convergence = running_mean(m.values, so.confidence);
        const double mean = m.summary->mean.value, sd = m.summary->std.value;
        if (auto it = options.ci_widths.find(name); it != options.ci_widths.end()) {
          m.target_width = it->second;
          m.target_source = "--ci-width";
        } else if (std::abs(mean) > 1e-12 * std::max(1.0, sd)) {
          m.target_width = 0.1 * std::abs(mean);
          m.target_source = "default: 10 % of |mean| (+-5 %)";
        } else {
          m.target_width = 0.1 * sd;
          m.target_source = "default: 10 % of the standard deviation";
        }
        m.runs_needed = runs_for_width(sd, m.target_width, so.confidence);
      }
    }
    if (m.headline && m.summary && !d.parameters.empty()) {
      try {
        if (d.is_saltelli()) {
          std::vector<double> y(n_rows, nan);
          for (std::size_t i = 0; i < n_rows; ++i) {
            const auto& row = d.rows[i];
            auto it = row.metrics.find(name);
            if (row.ok() && it != row.metrics.end()) y[i] = it->second;
          }
          m.sobol = sobol_indices(inputs, y, d.saltelli_base_size, options.stats);
          m.sensitivity_note =
              "Martinez estimator on " + std::to_string(m.sobol->base_size) + " complete base rows";
          if (m.sobol->base_dropped)
            m.sensitivity_note += " (" + std::to_string(m.sobol->base_dropped) +
                                  " left out: a run of their block failed or lacks the metric)";
        } else {
          std::vector<std::vector<double>> x;
          std::vector<double> y;
          for (std::size_t i : r.sample) {
            const auto& row = d.rows[i];
            auto it = row.metrics.find(name);
            if (!row.ok() || it == row.metrics.end()) continue;
            x.push_back(inputs[i]);
            y.push_back(it->second);
          }
          m.correlations = rank_correlations(x, y, options.stats);
          m.sensitivity_note = "rank correlations over " + std::to_string(m.correlations->n) + " ok runs";
        }
      } catch (const std::invalid_argument& e) {
        m.sensitivity_note = std::string("not computed: ") + e.what();
      }
    }
    r.metrics.push_back(std::move(m));
  }
  // Headline metrics first (debris summaries, then the rest by name), per-debris metrics last.
  std::stable_sort(r.metrics.begin(), r.metrics.end(), [](const MetricReport& a, const MetricReport& b) {
    auto rank = [](const MetricReport& m) {
      return m.headline ? (m.name.rfind("debris.", 0) == 0 ? 0 : 1) : 2;
    };
    return rank(a) < rank(b);
  });

  r.debris = analyse_debris(d, r.sample, options.cell_m, options.stats);
  r.surrogates = load_surrogates(options.db_file, d.record.id);
  return r;
}

void write_report(const Report& r) {
  const fs::path dir(r.options.out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw InputError(r.options.out_dir, "--out", "cannot create the output folder");
  const auto& d = r.data;
  const double conf = r.options.stats.confidence;

  // summary.json: every number the page shows.
  json j;
  j["campaign"] = {{"name", d.record.name},
                   {"db", d.db_file},
                   {"design", d.design_type},
                   {"model", d.model},
                   {"scene", d.scene},
                   {"code_version", d.record.code_version},
                   {"saltelli_base_size", d.saltelli_base_size},
                   {"design_points", d.rows.size()}};
  j["confidence"] = conf;
  j["bootstrap"] = r.options.stats.bootstrap;
  json counts = json::object();
  for (const auto& [s, n] : r.counts) counts[store::to_string(s)] = n;
  j["runs"] = {{"counts", counts},
               {"sample", r.sample_note},
               {"sample_points", r.sample.size()},
               {"sample_ok", r.sample_ok}};
  json failures = json::array();
  for (std::size_t i : r.not_ok)
    failures.push_back({{"design_index", d.rows[i].design_index},
                        {"run", d.rows[i].run_id},
                        {"status", store::to_string(d.rows[i].status)},
                        {"message", d.rows[i].message}});
  j["runs"]["not_ok"] = failures;
  json metrics = json::object();
  for (const auto& m : r.metrics) {
    json e = {{"headline", m.headline}, {"n", m.values.size()}, {"missing", m.missing}};
    if (m.summary) {
      const auto& s = *m.summary;
      e["mean"] = jest(s.mean);
      e["std"] = jest(s.std);
      e["min"] = s.min;
      e["max"] = s.max;
      for (const auto& q : s.quantiles) {
        char key[16];
        std::snprintf(key, sizeof key, "q%02d", static_cast<int>(std::lround(q.p * 100)));
        e[key] = jest(q.q);
        e[key]["ci_open"] = q.ci_open;
      }
      json ex = json::array();
      for (const auto& x : s.exceedances)
        ex.push_back({{"threshold", x.threshold}, {"count", x.count}, {"p", jest(x.p)}});
      e["exceedance"] = ex;
    }
    if (m.headline && m.summary) {
      e["convergence"] = {{"target_width", jnum(m.target_width)},
                          {"target", m.target_source},
                          {"runs_needed", m.runs_needed}};
      if (m.ecdf.half_width > 0) e["ecdf_band_half_width"] = m.ecdf.half_width;
    }
    if (m.sobol) {
      json s = json::object();
      for (std::size_t k = 0; k < r.sensitivity_inputs.size(); ++k)
        s[r.sensitivity_inputs[k]] = {{"first", jest(m.sobol->first[k])}, {"total", jest(m.sobol->total[k])}};
      e["sobol"] = s;
      e["sobol_base_size"] = m.sobol->base_size;
      e["sobol_base_dropped"] = m.sobol->base_dropped;
    }
    if (m.correlations) {
      json s = json::object();
      for (std::size_t k = 0; k < r.sensitivity_inputs.size(); ++k)
        s[r.sensitivity_inputs[k]] = {{"spearman", jest(m.correlations->spearman[k])},
                                      {"prcc", jest(m.correlations->prcc[k])}};
      e["rank_correlations"] = s;
    }
    if (!m.sensitivity_note.empty()) e["sensitivity_note"] = m.sensitivity_note;
    metrics[m.name] = e;
  }
  j["metrics"] = metrics;
  json groups = json::array();
  for (const auto& g : r.debris.groups) {
    json pr = json::array();
    for (const auto& p : g.probabilities)
      pr.push_back({{"what", p.what}, {"count", p.count}, {"n", p.n}, {"p", jest(p.p)}});
    groups.push_back({{"layout", g.layout},
                      {"layout_source", g.geometry.layout_source},
                      {"n_debris", g.n_debris},
                      {"runs", g.runs.size()},
                      {"cone_apex", {g.apex_x, g.apex_y}},
                      {"naito_deg", kNaitoSpreadingDeg},
                      {"nistor_eq59_deg", nistor_spreading_deg(g.n_debris)},
                      {"nistor_eq58_m", nistor_longitudinal_m(g.n_debris)},
                      {"probabilities", pr}});
  }
  json surrogates = json::array();
  for (const auto& s : r.surrogates) {
    json e = {{"metric", s.metric},         {"kind", s.kind},         {"n_train", s.n_train},
              {"n_holdout", s.n_holdout},   {"folds", s.folds},       {"q2_cv", jnum(s.q2_cv)},
              {"q2_holdout", jnum(s.q2_holdout)}, {"mean", s.mean},   {"std", s.std}};
    if (!s.condition.empty()) e["condition"] = s.condition;
    if (!s.first.empty()) {
      json sb = json::object();
      for (std::size_t k = 0; k < s.inputs.size() && k < s.first.size(); ++k)
        sb[s.inputs[k]] = {{"first", jest(s.first[k])}, {"total", jest(s.total[k])}};
      e["sobol"] = sb;
    }
    json curve = json::array();
    for (std::size_t i = 0; i < s.thresholds.size(); ++i)
      curve.push_back({{"threshold", s.thresholds[i]}, {"p", s.p[i]}, {"lo", jnum(s.p_lo[i])}, {"hi", jnum(s.p_hi[i])}});
    e["exceedance"] = curve;
    surrogates.push_back(e);
  }
  j["surrogates"] = surrogates;
  j["debris"] = {{"runs_with_debris", r.debris.runs_with_debris}, {"groups", groups}};
  write_text(dir / "summary.json", j.dump(2) + "\n");

  // CSV tables.
  {
    std::ostringstream o;
    o << "metric,n,missing,mean,mean_lo,mean_hi,std,std_lo,std_hi,q05,q05_lo,q05_hi,q50,q50_lo,q50_hi,q95,"
         "q95_lo,q95_hi,min,max\n";
    for (const auto& m : r.metrics) {
      if (!m.summary) continue;
      const auto& s = *m.summary;
      o << csv(m.name) << "," << m.values.size() << "," << m.missing;
      for (const Estimate& e : {s.mean, s.std, s.quantiles[0].q, s.quantiles[1].q, s.quantiles[2].q})
        o << "," << num(e.value) << "," << num(e.ci.lo) << "," << num(e.ci.hi);
      o << "," << num(s.min) << "," << num(s.max) << "\n";
    }
    write_text(dir / "metrics.csv", o.str());
  }
  {
    std::ostringstream o;
    o << "metric,threshold,count,n,p,p_lo,p_hi\n";
    for (const auto& m : r.metrics)
      if (m.summary)
        for (const auto& x : m.summary->exceedances)
          o << csv(m.name) << "," << num(x.threshold) << "," << x.count << "," << m.summary->n << ","
            << num(x.p.value) << "," << num(x.p.ci.lo) << "," << num(x.p.ci.hi) << "\n";
    write_text(dir / "exceedance.csv", o.str());
  }
  {
    std::ostringstream o;
    o << "metric,input,method,index,value,lo,hi\n";
    for (const auto& m : r.metrics)
      for (std::size_t k = 0; k < r.sensitivity_inputs.size(); ++k) {
        auto row = [&](const char* method, const char* index, const Estimate& e) {
          o << csv(m.name) << "," << csv(r.sensitivity_inputs[k]) << "," << method << "," << index << ","
            << num(e.value) << "," << num(e.ci.lo) << "," << num(e.ci.hi) << "\n";
        };
        if (m.sobol) {
          row("sobol_martinez", "first", m.sobol->first[k]);
          row("sobol_martinez", "total", m.sobol->total[k]);
        }
        if (m.correlations) {
          row("rank", "spearman", m.correlations->spearman[k]);
          row("rank", "prcc", m.correlations->prcc[k]);
        }
      }
    write_text(dir / "sensitivity.csv", o.str());
  }
  {
    std::ostringstream o;
    o << "metric,runs,running_mean,lo,hi\n";
    for (const auto& m : r.metrics)
      for (std::size_t k = 0; k < m.convergence.n.size(); ++k)
        o << csv(m.name) << "," << m.convergence.n[k] << "," << num(m.convergence.mean[k]) << ","
          << num(m.convergence.lo[k]) << "," << num(m.convergence.hi[k]) << "\n";
    write_text(dir / "convergence.csv", o.str());
  }
  {
    std::ostringstream o;
    o << "design_index,run,status,message\n";
    for (std::size_t i : r.not_ok)
      o << d.rows[i].design_index << "," << d.rows[i].run_id << "," << store::to_string(d.rows[i].status)
        << "," << csv(d.rows[i].message) << "\n";
    write_text(dir / "runs_not_ok.csv", o.str());
  }
  {
    std::ostringstream pos, pres;
    pos << "layout,n_debris,design_index,run,debris,initial_x_m,initial_y_m,runup_x_m,runup_y_m,rest_x_m,"
           "rest_y_m,"
           "spreading_runup_deg,spreading_rest_deg,dammed\n";
    pres << "layout,n_debris,x0_m,x1_m,y0_m,y1_m,p_runup,p_rest\n";
    for (const auto& g : r.debris.groups) {
      for (const auto& run : g.runs)
        for (const auto& db : run.debris)
          pos << g.layout << "," << g.n_debris << "," << d.rows[run.row].design_index << ","
              << d.rows[run.row].run_id << "," << db.k << "," << num(db.x0) << "," << num(db.y0) << ","
              << num(db.x_runup) << "," << num(db.y_runup) << "," << num(db.x_rest) << "," << num(db.y_rest)
              << "," << num(db.spreading_runup) << "," << num(db.spreading_rest) << "," << (db.dammed ? 1 : 0)
              << "\n";
      const auto& p = g.presence;
      const std::size_t nx = p.x_edges.size() - 1;
      for (std::size_t jy = 0; jy + 1 < p.y_edges.size(); ++jy)
        for (std::size_t ix = 0; ix < nx; ++ix)
          pres << g.layout << "," << g.n_debris << "," << num(p.x_edges[ix]) << "," << num(p.x_edges[ix + 1])
               << "," << num(p.y_edges[jy]) << "," << num(p.y_edges[jy + 1]) << ","
               << num(p.runup[jy * nx + ix]) << "," << num(p.rest[jy * nx + ix]) << "\n";
    }
    write_text(dir / "debris_positions.csv", pos.str());
    write_text(dir / "debris_presence.csv", pres.str());
  }
  write_text(dir / "report.html", render_html(r));
}

namespace {

// "metric=v1,v2" -> (metric, [v1, v2]); the metric name may itself contain '=' only before the last one.
std::pair<std::string, std::vector<double>> parse_metric_values(const std::string& text,
                                                                const std::string& option) {
  const auto eq = text.rfind('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw cli::UsageError(option, "expected metric=value[,value...] (got '" + text + "')");
  std::vector<double> values;
  std::stringstream ss(text.substr(eq + 1));
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v))
      throw cli::UsageError(option, "'" + item + "' in '" + text + "' is not a finite number");
    values.push_back(v);
  }
  return {text.substr(0, eq), values};
}

double parse_number(const std::string& text, const std::string& option, double lo, double hi, bool lo_open) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v) || (lo_open ? !(v > lo) : !(v >= lo)) || !(v <= hi)) {
    char range[96];
    std::snprintf(range, sizeof range, "%s%g, %g]", lo_open ? "(" : "[", lo, hi);
    throw cli::UsageError(option, "must be a number in " + std::string(range) + " (got '" + text + "')");
  }
  return v;
}

}  // namespace

void add_report_command(CLI::App& app) {
  struct Args {
    ReportOptions o;
    std::vector<std::string> thresholds, ci_widths;
    std::string confidence, bootstrap, cell, map_runs, seed;
  };
  auto a = std::make_shared<Args>();
  app.add_option("--db", a->o.db_file, "the campaign database")->required();
  app.add_option("--campaign", a->o.campaign, "the campaign (default: the only one)");
  app.add_option("--out", a->o.out_dir, "the folder report.html, report.json and the CSVs go to")->required();
  app.add_option("--thresholds", a->thresholds, "exceedance thresholds, several may follow one flag")
      ->type_name("METRIC=V1,V2");
  app.add_option("--ci-width", a->ci_widths, "the confidence-interval width wanted for a metric (repeatable)")
      ->allow_extra_args(false)
      ->type_name("METRIC=W");
  app.add_option("--confidence", a->confidence, "confidence level of the intervals, in [0.5, 0.999] (default 0.95)");
  app.add_option("--bootstrap", a->bootstrap, "bootstrap resamples, in [100, 100000] (default 1000)");
  app.add_option("--cell", a->cell, "map cell size (m), in [0.01, 2] (default 0.25)");
  app.add_option("--map-runs", a->map_runs, "runs drawn on the map, in [1, 1e6] (default 1000)");
  app.add_option("--seed", a->seed, "the bootstrap's seed (default 1)");
  cli::on_parse(app, [a]() -> int {
    ReportOptions o = a->o;
    for (const auto& text : a->thresholds) {
      auto [metric, values] = parse_metric_values(text, "--thresholds");
      auto& t = o.thresholds[metric];
      t.insert(t.end(), values.begin(), values.end());
    }
    for (const auto& text : a->ci_widths) {
      auto [metric, values] = parse_metric_values(text, "--ci-width");
      if (values.size() != 1 || !(values[0] > 0))
        throw cli::UsageError("--ci-width", "expected metric=w with one width w > 0");
      o.ci_widths[metric] = values[0];
    }
    if (!a->confidence.empty()) o.stats.confidence = parse_number(a->confidence, "--confidence", 0.5, 0.999, false);
    if (!a->bootstrap.empty())
      o.stats.bootstrap = static_cast<std::size_t>(parse_number(a->bootstrap, "--bootstrap", 100, 100000, false));
    if (!a->cell.empty()) o.cell_m = parse_number(a->cell, "--cell", 0.01, 2.0, false);
    if (!a->map_runs.empty())
      o.map_runs = static_cast<std::size_t>(parse_number(a->map_runs, "--map-runs", 1, 1e6, false));
    if (!a->seed.empty())
      o.stats.seed = static_cast<std::uint64_t>(parse_number(a->seed, "--seed", 0, 4294967295.0, false));
    const Report r = build_report(o);
    write_report(r);
    std::printf("report: %s/report.html (%zu of %zu sample runs ok; %zu metrics)\n", o.out_dir.c_str(),
                r.sample_ok, r.sample.size(), r.metrics.size());
    return kExitOk;
  });
}

}  // namespace flume::report
