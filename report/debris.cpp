#include "report/debris.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

namespace flume::report {
namespace {

constexpr double kDeg = 180.0 / M_PI;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Probability proportion(std::string what, std::size_t count, std::size_t n, double confidence,
                       bool with_ci = true) {
  Probability p;
  p.what = std::move(what);
  p.count = count;
  p.n = n;
  p.p.value = n ? static_cast<double>(count) / n : std::nan("");
  p.p.ci = with_ci && n ? clopper_pearson(count, n, confidence) : Interval{std::nan(""), std::nan("")};
  return p;
}

std::vector<double> edges(double lo, double hi, double cell) {
  const int n = std::max(1, static_cast<int>(std::lround((hi - lo) / cell)));
  std::vector<double> e;
  for (int i = 0; i <= n; ++i) e.push_back(lo + (hi - lo) * i / n);
  return e;
}

int cell_of(const std::vector<double>& e, double v) {
  if (!(v >= e.front() && v <= e.back())) return -1;
  const auto it = std::upper_bound(e.begin(), e.end(), v);
  return std::min(static_cast<int>(it - e.begin()) - 1, static_cast<int>(e.size()) - 2);
}

}  // namespace

std::vector<DebrisState> debris_of(const std::map<std::string, double>& m) {
  std::vector<DebrisState> out;
  for (int k = 1; k <= 64; ++k) {
    std::string p = "D";
    p += std::to_string(k);
    p += '.';
    auto get = [&](const char* name, double& v) {
      auto it = m.find(p + name);
      if (it == m.end()) return false;
      v = it->second;
      return true;
    };
    DebrisState d;
    d.k = k;
    if (!get("runup_x_m", d.x_runup)) break;
    if (!get("initial_x_m", d.x0) || !get("initial_y_m", d.y0) || !get("runup_y_m", d.y_runup) ||
        !get("rest_x_m", d.x_rest) || !get("rest_y_m", d.y_rest))
      continue;
    if (!get("longitudinal_max_m", d.longitudinal_max)) d.longitudinal_max = d.x_runup - d.x0;
    if (!get("longitudinal_rest_m", d.longitudinal_rest)) d.longitudinal_rest = d.x_rest - d.x0;
    if (!get("spreading_runup_deg", d.spreading_runup))
      d.spreading_runup = std::atan2(d.y_runup - d.y0, d.x_runup - d.x0) * kDeg;
    if (!get("spreading_rest_deg", d.spreading_rest))
      d.spreading_rest = std::atan2(d.y_rest - d.y0, d.x_rest - d.x0) * kDeg;
    double dammed = 0;
    d.dammed = get("dammed", dammed) && dammed > 0.5;
    double at_rest = 0;
    if (get("at_rest", at_rest)) d.at_rest = at_rest > 0.5 ? 1 : 0;
    out.push_back(d);
  }
  return out;
}

std::map<std::string, double> derived_debris_metrics(const std::vector<DebrisState>& debris,
                                                     double quay_x_m) {
  std::map<std::string, double> m;
  if (debris.empty()) return m;
  std::vector<double> lmax, lrest;
  double s_run = 0, s_rest = 0, r_run = -1e300, r_rest = -1e300, dammed = 0, moving = 0;
  bool rest_known = true;
  for (const auto& d : debris) {
    rest_known &= d.at_rest >= 0;
    moving += d.at_rest == 0;
    s_run = std::max(s_run, std::abs(d.spreading_runup));
    s_rest = std::max(s_rest, std::abs(d.spreading_rest));
    r_run = std::max(r_run, d.x_runup - quay_x_m);
    r_rest = std::max(r_rest, d.x_rest - quay_x_m);
    lmax.push_back(d.longitudinal_max);
    lrest.push_back(d.longitudinal_rest);
    dammed += d.dammed;
  }
  m["debris.count"] = static_cast<double>(debris.size());
  m["debris.spreading_runup_max_abs_deg"] = s_run;
  m["debris.spreading_rest_max_abs_deg"] = s_rest;
  m["debris.longitudinal_max_median_m"] = median(lmax);
  m["debris.longitudinal_rest_median_m"] = median(lrest);
  m["debris.runout_runup_max_m"] = r_run;
  m["debris.runout_rest_max_m"] = r_rest;
  m["debris.dammed_count"] = dammed;
  if (rest_known) m["debris.moving_count"] = moving;
  return m;
}

DebrisAnalysis analyse_debris(const CampaignData& data, const std::vector<std::size_t>& sample, double cell_m,
                              const StatsOptions& opt) {
  DebrisAnalysis a;
  std::map<std::pair<std::string, int>, DebrisGroup> groups;
  for (std::size_t r : sample) {
    const RunRow& row = data.rows[r];
    if (!row.ok()) continue;
    DebrisRun run{r, debris_of(row.metrics)};
    if (run.debris.empty()) continue;
    const ApronGeometry g = apron_geometry(data, &row);
    DebrisGroup& grp = groups[{g.layout, static_cast<int>(run.debris.size())}];
    grp.layout = g.layout;
    grp.n_debris = static_cast<int>(run.debris.size());
    grp.geometry = g;
    grp.runs.push_back(std::move(run));
    ++a.runs_with_debris;
  }
  for (auto& [key, g] : groups) {
    const std::size_t n = g.runs.size();
    const double theta_n = nistor_spreading_deg(g.n_debris), long_n = nistor_longitudinal_m(g.n_debris);
    double sx = 0, sy = 0;
    std::size_t count = 0;
    std::size_t naito_run = 0, naito_rest = 0, nistor_run = 0, nistor_rest = 0, long_above = 0,
                any_dammed = 0, any_moving = 0, rest_known = 0;
    std::size_t debris_total = 0, debris_naito_run = 0, debris_naito_rest = 0;
    std::vector<double> runout_run, runout_rest;
    const auto& geo = g.geometry;
    g.presence.x_edges = edges(geo.quay_x_m, geo.end_x_m, cell_m);
    g.presence.y_edges = edges(geo.y_lo_m, geo.y_hi_m, cell_m);
    const std::size_t nx = g.presence.x_edges.size() - 1, ny = g.presence.y_edges.size() - 1;
    g.presence.runup.assign(nx * ny, 0.0);
    g.presence.rest.assign(nx * ny, 0.0);
    for (const auto& run : g.runs) {
      const auto derived = derived_debris_metrics(run.debris, geo.quay_x_m);
      const double s_run = derived.at("debris.spreading_runup_max_abs_deg");
      const double s_rest = derived.at("debris.spreading_rest_max_abs_deg");
      naito_run += s_run > kNaitoSpreadingDeg;
      naito_rest += s_rest > kNaitoSpreadingDeg;
      nistor_run += s_run > theta_n;
      nistor_rest += s_rest > theta_n;
      long_above += derived.at("debris.longitudinal_max_median_m") > long_n;
      any_dammed += derived.at("debris.dammed_count") > 0;
      if (const auto it = derived.find("debris.moving_count"); it != derived.end()) {
        ++rest_known;
        any_moving += it->second > 0;
      }
      runout_run.push_back(derived.at("debris.runout_runup_max_m"));
      runout_rest.push_back(derived.at("debris.runout_rest_max_m"));
      std::set<int> cells_run, cells_rest;  // a run counts once per cell, however many debris are in it
      for (const auto& d : run.debris) {
        sx += d.x0;
        sy += d.y0;
        ++count;
        ++debris_total;
        debris_naito_run += std::abs(d.spreading_runup) > kNaitoSpreadingDeg;
        debris_naito_rest += std::abs(d.spreading_rest) > kNaitoSpreadingDeg;
        const int ir = cell_of(g.presence.x_edges, d.x_runup), jr = cell_of(g.presence.y_edges, d.y_runup);
        if (ir >= 0 && jr >= 0) cells_run.insert(jr * static_cast<int>(nx) + ir);
        const int is = cell_of(g.presence.x_edges, d.x_rest), js = cell_of(g.presence.y_edges, d.y_rest);
        if (is >= 0 && js >= 0) cells_rest.insert(js * static_cast<int>(nx) + is);
      }
      for (int c : cells_run) g.presence.runup[c] += 1.0 / n;
      for (int c : cells_rest) g.presence.rest[c] += 1.0 / n;
    }
    g.apex_x = count ? sx / count : geo.quay_x_m;
    g.apex_y = count ? sy / count : 0.5 * (geo.y_lo_m + geo.y_hi_m);
    const double c = opt.confidence;
    char buf[160];
    g.probabilities.push_back(
        proportion("P(a spreading angle at run-up > 22.5 deg, Naito)", naito_run, n, c));
    g.probabilities.push_back(proportion("P(a spreading angle at rest > 22.5 deg, Naito)", naito_rest, n, c));
    std::snprintf(buf, sizeof buf, "P(a spreading angle at run-up > %.2f deg, Nistor eq. 59, N = %d)",
                  theta_n, g.n_debris);
    g.probabilities.push_back(proportion(buf, nistor_run, n, c));
    std::snprintf(buf, sizeof buf, "P(a spreading angle at rest > %.2f deg, Nistor eq. 59, N = %d)", theta_n,
                  g.n_debris);
    g.probabilities.push_back(proportion(buf, nistor_rest, n, c));
    std::snprintf(buf, sizeof buf, "P(median longitudinal displacement > %.2f m, Nistor eq. 58, N = %d)",
                  long_n, g.n_debris);
    g.probabilities.push_back(proportion(buf, long_above, n, c));
    g.probabilities.push_back(proportion("P(at least one debris dammed)", any_dammed, n, c));
    // The "rest" positions above are where the debris were when the run ended: this says how often that was
    // not yet rest (runs of an older solver, without D<k>.at_rest, are left out of it).
    if (rest_known > 0)
      g.probabilities.push_back(proportion("P(a debris not at rest when the run ended: its 'rest' is where it was then)",
                                           any_moving, rest_known, c));
    g.probabilities.push_back(
        proportion("fraction of debris with |spreading at run-up| > 22.5 deg (no CI: debris of a run are not "
                   "independent)",
                   debris_naito_run, debris_total, c, false));
    g.probabilities.push_back(proportion(
        "fraction of debris with |spreading at rest| > 22.5 deg (no CI: debris of a run are not independent)",
        debris_naito_rest, debris_total, c, false));
    g.runout_runup = ecdf_band(runout_run, opt);
    g.runout_rest = ecdf_band(runout_rest, opt);
    a.groups.push_back(std::move(g));
  }
  return a;
}

}  // namespace flume::report
