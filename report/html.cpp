// report.html: one self-contained page. Figures are inline SVG from flume_plot, styling is inline CSS, and
// the only script is an inline check that records which sections drew (the headless-browser test reads it).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <sstream>

#include "common/plot/figure.h"
#include "common/version.h"
#include "report/html_parts.h"
#include "report/map.h"
#include "report/report.h"
#include "report/surrogates.h"

namespace flume::report {
namespace {

namespace plot = flume::plot;
using plot::xml_escape;

using namespace html;

int bins_for(std::size_t n) { return std::clamp(static_cast<int>(std::sqrt(static_cast<double>(n))), 8, 40); }

// --------------------------------------------------------------------------------------------- sections

void runs_section(std::ostringstream& h, const Report& r) {
  const auto& d = r.data;
  std::size_t distinct = 0;
  for (const auto& [s, n] : r.counts) distinct += n;
  h << "<section id=runs><h2>Runs</h2>\n<table class=small><tr>";
  for (const char* s : {"ok", "unstable", "failed", "timeout", "pending", "running"})
    h << "<th>" << s << "</th>";
  h << "<th>total</th></tr><tr>";
  for (auto s : {store::RunStatus::kOk, store::RunStatus::kUnstable, store::RunStatus::kFailed,
                 store::RunStatus::kTimeout, store::RunStatus::kPending, store::RunStatus::kRunning}) {
    auto it = r.counts.find(s);
    h << "<td>" << (it == r.counts.end() ? 0 : it->second) << "</td>";
  }
  h << "<td>" << distinct << "</td></tr></table>\n";
  const std::size_t left_out = r.sample.size() - r.sample_ok;
  h << "<p class=rests id=rests-on><b>The statistics rest on " << r.sample_ok << " of " << r.sample.size()
    << " runs</b>: " << xml_escape(r.sample_note) << ".";
  if (left_out)
    h << " <b>" << left_out
      << " of them did not end ok and are left out</b> (listed below); every statistic is "
      << "computed on the runs that did, which is unbiased only if a run's failure does not depend on its "
         "outcome.";
  else
    h << " Every run of the sample ended ok.";
  h << "</p>\n";
  if (!r.not_ok.empty()) {
    h << "<table id=failures><tr><th>design index</th><th>run</th><th>status</th><th>message</th></tr>\n";
    for (std::size_t i : r.not_ok)
      h << "<tr><td>" << d.rows[i].design_index << "</td><td>" << d.rows[i].run_id << "</td><td class=st-"
        << store::to_string(d.rows[i].status) << ">" << store::to_string(d.rows[i].status) << "</td><td>"
        << xml_escape(d.rows[i].message.empty() ? "(no message)" : d.rows[i].message) << "</td></tr>\n";
    h << "</table>\n";
  }
  h << "</section>\n";
}

void debris_section(std::ostringstream& h, const Report& r) {
  h << "<section id=debris><h2>Debris spreading</h2>\n";
  if (r.debris.groups.empty()) {
    h << "<p class=note>No debris metrics (D&lt;k&gt;.runup_x_m ...) in the ok runs of this campaign: "
         "nothing to "
         "map.</p></section>\n";
    return;
  }
  const double conf = r.options.stats.confidence;
  for (const auto& g : r.debris.groups) {
    const double theta_n = nistor_spreading_deg(g.n_debris), long_n = nistor_longitudinal_m(g.n_debris);
    h << "<div class=group><h3>Obstacle layout " << xml_escape(g.layout) << " ("
      << xml_escape(g.geometry.layout_source) << "), " << g.n_debris << " debris, " << g.runs.size()
      << " runs</h3>\n";

    // The map: positions of every debris of every run (up to --map-runs runs) and the guideline cones.
    {
      plot::Figure fig(1, 1, 980, 560);
      auto& ax = fig.axes();
      const std::size_t drawn = std::min(g.runs.size(), r.options.map_runs);
      char title[200];
      std::snprintf(title, sizeof title,
                    "Top-down apron: run-up and rest positions of every debris (%zu runs)", drawn);
      ax.title(title);
      draw_apron(ax, g.geometry);
      draw_cone(ax, g.apex_x, g.apex_y, g.geometry.end_x_m, kNaitoSpreadingDeg, kVermillion, plot::Dash::kDashed,
                "Naito 22.5 deg");
      char lab[64];
      std::snprintf(lab, sizeof lab, "Nistor eq. 59: %.2f deg", theta_n);
      draw_cone(ax, g.apex_x, g.apex_y, g.geometry.end_x_m, theta_n, kPurple, plot::Dash::kDotted, lab);
      std::vector<double> x0, y0, xr, yr, xs, ys;
      for (std::size_t k = 0; k < drawn; ++k)
        for (const auto& db : g.runs[k].debris) {
          x0.push_back(db.x0);
          y0.push_back(db.y0);
          xr.push_back(db.x_runup);
          yr.push_back(db.y_runup);
          xs.push_back(db.x_rest);
          ys.push_back(db.y_rest);
        }
      const double op = std::clamp(20.0 / std::sqrt(static_cast<double>(xr.size() + 1)), 0.15, 0.8);
      ax.scatter(
          xr, yr,
          {.color = kBlue, .marker = plot::Marker::kCircle, .size = 4, .opacity = op, .label = "run-up"});
      ax.scatter(
          xs, ys,
          {.color = kOrange, .marker = plot::Marker::kDiamond, .size = 4, .opacity = op, .label = "rest"});
      ax.scatter(
          x0, y0,
          {.color = plot::Color{0, 0, 0}, .marker = plot::Marker::kSquare, .size = 5, .label = "initial"});
      ax.legend(plot::Legend::kUpperRight);
      h << "<figure class=map>" << svg_or_note(fig)
        << "<figcaption>Quay wall at x = " << fmt(g.geometry.quay_x_m)
        << " m (thick line), basin to its left, obstacles in black. Cones from the mean initial debris "
           "position ("
        << fmt(g.apex_x, 3) << ", " << fmt(g.apex_y, 3)
        << ") m: Naito et al. (2014) 22.5 deg and Nistor et al. "
        << "(2017) eq. 59, 3.69 + 0.80 N = " << fmt(theta_n) << " deg for N = " << g.n_debris << ".";
      if (drawn < g.runs.size())
        h << " Positions of the first " << drawn << " of " << g.runs.size()
          << " runs are drawn (--map-runs); every run enters the probabilities and maps below.";
      h << "</figcaption></figure>\n";
    }

    // Probabilities with their intervals.
    h << "<table class=prob><tr><th>event (per run)</th><th>runs</th><th>probability [" << pct(conf)
      << " Clopper-Pearson]</th></tr>\n";
    for (const auto& p : g.probabilities)
      h << "<tr><td>" << xml_escape(p.what) << "</td><td>" << p.count << " / " << p.n << "</td><td>"
        << (std::isnan(p.p.ci.lo) ? fmt(p.p.value, 3) : est(p.p, 3)) << "</td></tr>\n";
    h << "</table>\n";

    // Presence maps.
    {
      plot::Figure fig(1, 2, 980, 330);
      const char* titles[2] = {"P(a debris at run-up in the cell)", "P(a debris at rest in the cell)"};
      for (int c = 0; c < 2; ++c) {
        auto& ax = fig.axes(0, c);
        ax.title(titles[c])
            .equal_aspect()
            .xlim(g.geometry.quay_x_m, g.geometry.end_x_m)
            .ylim(g.geometry.y_lo_m, g.geometry.y_hi_m)
            .xlabel("x [m]")
            .ylabel("y [m]");
        std::vector<double> v = c == 0 ? g.presence.runup : g.presence.rest;
        for (double& p : v)
          if (p == 0) p = std::nan("");  // empty cells left blank
        ax.heatmap(g.presence.x_edges, g.presence.y_edges, v,
                   {.vmin = 0.0, .vmax = 1.0, .colorbar_label = "P"});
        for (const auto& o : g.geometry.obstacles)
          ax.rect(o.x0, o.y0, o.x1, o.y1, {.color = plot::Color{220, 40, 40}, .opacity = 0.9});
      }
      h << "<figure>" << svg_or_note(fig) << "<figcaption>Debris-presence probability: the fraction of the "
        << g.runs.size() << " runs that put at least one debris centre in each " << fmt(r.options.cell_m, 3)
        << " m cell (blank: none). Obstacles in red.</figcaption></figure>\n";
    }

    // Spreading angles, longitudinal displacement, run-out.
    {
      std::vector<double> s_run, s_rest, l_max, l_rest;
      for (const auto& run : g.runs)
        for (const auto& db : run.debris) {
          s_run.push_back(db.spreading_runup);
          s_rest.push_back(db.spreading_rest);
          l_max.push_back(db.longitudinal_max);
          l_rest.push_back(db.longitudinal_rest);
        }
      plot::Figure fig(1, 2, 980, 330);
      auto& a = fig.axes(0, 0);
      a.title("Spreading angle of every debris").xlabel("angle [deg]").ylabel("debris");
      a.histogram(s_run, bins_for(s_run.size()), {.color = kBlue, .opacity = 0.45, .label = "run-up"});
      a.histogram(s_rest, bins_for(s_rest.size()), {.color = kOrange, .opacity = 0.45, .label = "rest"});
      for (double sgn : {-1.0, 1.0}) {
        a.vline(
            sgn * kNaitoSpreadingDeg,
            {.color = kVermillion, .dash = plot::Dash::kDashed, .label = sgn > 0 ? "Naito +-22.5 deg" : ""});
        a.vline(sgn * theta_n,
                {.color = kPurple, .dash = plot::Dash::kDotted, .label = sgn > 0 ? "Nistor eq. 59" : ""});
      }
      a.legend(plot::Legend::kUpperLeft);
      auto& b = fig.axes(0, 1);
      b.title("Longitudinal displacement of every debris").xlabel("displacement [m]").ylabel("debris");
      b.histogram(l_max, bins_for(l_max.size()),
                  {.color = kBlue, .opacity = 0.45, .label = "maximum (run-up)"});
      b.histogram(l_rest, bins_for(l_rest.size()), {.color = kOrange, .opacity = 0.45, .label = "at rest"});
      char lab[64];
      std::snprintf(lab, sizeof lab, "Nistor eq. 58: %.2f m", long_n);
      b.vline(long_n, {.color = kPurple, .width = 2, .dash = plot::Dash::kDashed, .label = lab});
      b.legend(plot::Legend::kUpperLeft);
      h << "<figure>" << svg_or_note(fig)
        << "<figcaption>Every debris of every run. Nistor et al. (2017) eq. 58 "
        << "predicts the median longitudinal displacement 3.58 - 0.09 N = " << fmt(long_n)
        << " m (Waseda flume only).</figcaption></figure>\n";
    }
    {
      plot::Figure fig(1, 1, 980, 330);
      auto& ax = fig.axes();
      ax.title("Run-out past the quay wall: exceedance of the farthest debris per run")
          .xlabel("distance past the quay wall [m]")
          .ylabel("P(run-out > d)")
          .ylim(0, 1);
      auto curve = [&](const EcdfBand& e, const plot::Color& c, const std::string& label) {
        if (e.x.empty()) return;
        std::vector<double> x{e.x.front()}, p{1.0}, lo{1.0}, hi{1.0};
        for (std::size_t i = 0; i < e.x.size(); ++i) {
          x.push_back(e.x[i]);
          p.push_back(1 - e.f[i]);
          lo.push_back(1 - e.hi[i]);
          hi.push_back(1 - e.lo[i]);
        }
        ax.band(x, lo, hi, {.color = c, .opacity = 0.2});
        ax.step(x, p, {.color = c, .width = 2, .label = label}, plot::Step::kPost);
      };
      curve(g.runout_runup, kBlue, "at run-up");
      curve(g.runout_rest, kOrange, "at rest");
      ax.vline(g.geometry.end_x_m - g.geometry.quay_x_m,
               {.color = kGrey, .dash = plot::Dash::kDashed, .label = "back wall"});
      ax.legend(plot::Legend::kUpperRight);
      h << "<figure>" << svg_or_note(fig)
        << "<figcaption>1 - F of the farthest debris' distance past the quay wall, with "
        << "the " << pct(conf) << " simultaneous bootstrap band (half-width "
        << fmt(g.runout_runup.half_width, 3) << " at run-up, " << fmt(g.runout_rest.half_width, 3)
        << " at rest).</figcaption></figure>\n";
    }
    h << "</div>\n";
  }
  h << "</section>\n";
}

void metric_card(std::ostringstream& h, const MetricReport& m, const Report& r) {
  const auto& s = *m.summary;
  const double conf = r.options.stats.confidence;
  h << "<div class=metric id=\"m-" << xml_escape(m.name) << "\"><h3>" << xml_escape(m.name) << "</h3>\n";
  h << "<p class=rests>On " << s.n << " runs";
  if (m.missing) h << " (" << m.missing << " ok runs lack this metric)";
  h << ".</p>\n<table class=small><tr><th>mean</th><th>std</th><th>5 %</th><th>50 %</th><th>95 "
       "%</th><th>min</th><th>max</th></tr><tr><td>"
    << est(s.mean) << "</td><td>" << est(s.std) << "</td>";
  for (const auto& q : s.quantiles)
    h << "<td>" << est(q.q) << (q.ci_open ? " <span class=warn>(open)</span>" : "") << "</td>";
  h << "<td>" << fmt(s.min) << "</td><td>" << fmt(s.max) << "</td></tr></table>\n";
  if (!s.exceedances.empty()) {
    h << "<table class=small><tr><th>threshold</th><th>runs above</th><th>P(&gt; threshold) [" << pct(conf)
      << "]</th></tr>";
    for (const auto& e : s.exceedances)
      h << "<tr><td>" << fmt(e.threshold) << "</td><td>" << e.count << " / " << s.n << "</td><td>"
        << est(e.p, 3) << "</td></tr>";
    h << "</table>\n";
  }
  plot::Figure fig(1, 2, 980, 300);
  auto& a = fig.axes(0, 0);
  a.title("Histogram").xlabel(m.name).ylabel("runs");
  a.histogram(m.values, bins_for(m.values.size()), {.color = kBlue, .opacity = 0.5});
  a.vline(s.quantiles[1].q.value, {.color = kGrey, .dash = plot::Dash::kDashed, .label = "median"});
  auto& b = fig.axes(0, 1);
  b.title("Empirical CDF, " + pct(conf) + " bootstrap band").xlabel(m.name).ylabel("F").ylim(0, 1);
  if (!m.ecdf.x.empty()) {
    std::vector<double> x{m.ecdf.x.front()}, f{0.0}, lo{0.0}, hi{std::min(1.0, m.ecdf.half_width)};
    for (std::size_t i = 0; i < m.ecdf.x.size(); ++i) {
      x.push_back(m.ecdf.x[i]);
      f.push_back(m.ecdf.f[i]);
      lo.push_back(m.ecdf.lo[i]);
      hi.push_back(m.ecdf.hi[i]);
    }
    b.band(x, lo, hi, {.color = kBlue, .opacity = 0.2, .label = "band"});
    b.step(x, f, {.color = kBlue, .width = 1.8, .label = "F_n"}, plot::Step::kPost);
  }
  for (const auto& e : s.exceedances) {
    a.vline(e.threshold, {.color = kVermillion, .dash = plot::Dash::kDotted});
    b.vline(e.threshold, {.color = kVermillion, .dash = plot::Dash::kDotted});
  }
  b.legend(plot::Legend::kLowerRight);
  h << svg_or_note(fig) << "</div>\n";
}

void metrics_section(std::ostringstream& h, const Report& r) {
  const double conf = r.options.stats.confidence;
  h << "<section id=metrics><h2>Metrics</h2>\n<p>Each value is followed by its " << pct(conf)
    << " confidence interval in brackets: the mean by Student's t, the standard deviation by percentile "
       "bootstrap ("
    << r.options.stats.bootstrap << " resamples), quantiles by order statistics (distribution-free), "
    << "exceedance probabilities by Clopper-Pearson. '(open)': too few runs for a two-sided quantile "
       "interval; "
    << "the sample extreme is shown.</p>\n";
  bool any = false;
  for (const auto& m : r.metrics)
    if (m.headline && m.summary) {
      metric_card(h, m, r);
      any = true;
    }
  for (const auto& m : r.metrics)
    if (m.headline && !m.summary)
      h << "<p class=note>" << xml_escape(m.name) << ": fewer than 2 values (" << m.values.size()
        << "), no statistics.</p>\n";
  if (!any) h << "<p class=note>No metric has two or more values.</p>\n";
  bool debris_rows =
      std::any_of(r.metrics.begin(), r.metrics.end(), [](const auto& m) { return !m.headline; });
  if (debris_rows) {
    h << "<details><summary>Per-debris metrics (D&lt;k&gt;.*)</summary>\n<table "
         "class=small><tr><th>metric</th><th>n</th>"
      << "<th>mean</th><th>std</th><th>5 %</th><th>50 %</th><th>95 %</th></tr>\n";
    for (const auto& m : r.metrics) {
      if (m.headline || !m.summary) continue;
      const auto& s = *m.summary;
      h << "<tr><td>" << xml_escape(m.name) << "</td><td>" << s.n << "</td><td>" << est(s.mean) << "</td><td>"
        << est(s.std) << "</td>";
      for (const auto& q : s.quantiles) h << "<td>" << est(q.q) << "</td>";
      h << "</tr>\n";
    }
    h << "</table></details>\n";
  }
  h << "</section>\n";
}

void sensitivity_section(std::ostringstream& h, const Report& r) {
  const double conf = r.options.stats.confidence;
  h << "<section id=sensitivity><h2>Sensitivity</h2>\n";
  if (r.sensitivity_inputs.empty()) {
    h << "<p class=note>The campaign has no parameters.</p></section>\n";
    return;
  }
  if (r.data.is_saltelli())
    h << "<p>Saltelli design, base size N = " << r.data.saltelli_base_size
      << ": first-order (S) and total (ST) Sobol' indices by the Martinez estimator (OpenTURNS), "
      << pct(conf)
      << " bootstrap intervals. S is the share of the output variance explained by the input alone, ST "
         "includes "
      << "its interactions; ST - S large means interactions.</p>\n";
  else
    h << "<p>" << xml_escape(r.data.design_type)
      << " design: Spearman rank correlation and partial rank correlation "
      << "(PRCC, the rank correlation once the other inputs are accounted for), OpenTURNS, " << pct(conf)
      << " bootstrap intervals. They measure monotone effects only.</p>\n";
  bool any = false;
  for (const auto& m : r.metrics) {
    if (!m.headline || !m.summary) continue;
    if (!m.sobol && !m.correlations) {
      if (!m.sensitivity_note.empty())
        h << "<p class=note>" << xml_escape(m.name) << ": " << xml_escape(m.sensitivity_note) << "</p>\n";
      continue;
    }
    any = true;
    h << "<div class=sens><h3>" << xml_escape(m.name) << "</h3><p class=rests>"
      << xml_escape(m.sensitivity_note) << ".</p>\n<table class=small><tr><th>input</th>";
    if (m.sobol)
      h << "<th>first order S</th><th></th><th>total ST</th><th></th></tr>\n";
    else
      h << "<th>Spearman</th><th></th><th>PRCC</th><th></th></tr>\n";
    for (std::size_t k = 0; k < r.sensitivity_inputs.size(); ++k) {
      const Estimate& a = m.sobol ? m.sobol->first[k] : m.correlations->spearman[k];
      const Estimate& b = m.sobol ? m.sobol->total[k] : m.correlations->prcc[k];
      h << "<tr><td>" << xml_escape(r.sensitivity_inputs[k]) << "</td><td>" << est(a, 3) << "</td><td>"
        << bar(a.value, kBlue) << "</td><td>" << est(b, 3) << "</td><td>" << bar(b.value, kOrange)
        << "</td></tr>\n";
    }
    h << "</table></div>\n";
  }
  if (!any) h << "<p class=note>No sensitivity could be computed.</p>\n";
  h << "</section>\n";
}

void convergence_section(std::ostringstream& h, const Report& r) {
  const double conf = r.options.stats.confidence;
  h << "<section id=convergence><h2>Convergence</h2>\n<p>Running mean over the runs in design order with its "
    << pct(conf)
    << " Student interval. 'Runs needed' is the smallest n whose interval of the mean is the target "
    << "width at the current standard deviation (set a target with --ci-width metric=w).</p>\n"
    << "<table class=small><tr><th>metric</th><th>runs</th><th>interval width now</th><th>target width</th>"
    << "<th>runs needed</th></tr>\n";
  for (const auto& m : r.metrics) {
    if (!m.headline || !m.summary) continue;
    const double now = m.summary->mean.ci.hi - m.summary->mean.ci.lo;
    h << "<tr><td>" << xml_escape(m.name) << "</td><td>" << m.summary->n << "</td><td>" << fmt(now, 3)
      << "</td><td>" << fmt(m.target_width, 3) << " <span class=ci>(" << xml_escape(m.target_source)
      << ")</span></td><td>" << m.runs_needed << (m.runs_needed <= m.summary->n ? " (reached)" : "")
      << "</td></tr>\n";
  }
  h << "</table>\n<div class=grid>\n";
  for (const auto& m : r.metrics) {
    if (!m.headline || !m.summary || m.convergence.n.size() < 2) continue;
    plot::Figure fig(1, 1, 480, 260);
    auto& ax = fig.axes();
    ax.title(m.name).xlabel("runs").ylabel("running mean");
    ax.band(m.convergence.n, m.convergence.lo, m.convergence.hi, {.color = kBlue, .opacity = 0.2});
    ax.line(m.convergence.n, m.convergence.mean, {.color = kBlue, .width = 1.6});
    ax.hline(m.summary->mean.value, {.color = kGrey, .dash = plot::Dash::kDashed});
    h << "<div>" << svg_or_note(fig) << "</div>\n";
  }
  h << "</div></section>\n";
}

const char* kStyle = R"CSS(
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,Helvetica,Arial,sans-serif;margin:0 auto;max-width:1040px;padding:0 16px 40px;color:#222}
h1{font-size:1.6em;margin-bottom:.2em} h2{border-bottom:2px solid #0072b2;padding-bottom:2px;margin-top:1.6em}
h3{margin:1.2em 0 .3em} nav a{margin-right:1em} .meta{color:#555;font-size:.9em}
table{border-collapse:collapse;margin:.4em 0} td,th{border:1px solid #ccc;padding:3px 7px;text-align:left;vertical-align:top}
th{background:#f2f6fa} .small{font-size:.88em} .ci{color:#666;font-size:.92em} .note{color:#8a5a00}
.warn{color:#b03000} .rests{color:#333;margin:.2em 0} .bar{display:inline-block;height:10px}
.st-failed,.st-unstable,.st-timeout{color:#b03000;font-weight:600} figure{margin:.6em 0} figcaption{font-size:.88em;color:#444}
.grid{display:flex;flex-wrap:wrap;gap:8px} .metric,.group,.sens{border-top:1px solid #ddd;padding-top:4px}
svg{max-width:100%;height:auto}
)CSS";

// Records, per section, how many figures have a non-empty box and drawn shapes; the headless test reads it.
const char* kCheckScript = R"JS(
(function () {
  var ids = ["runs", "debris", "metrics", "sensitivity", "convergence"];
  var parts = [];
  var missing = 0;
  ids.forEach(function (id) {
    var s = document.getElementById(id);
    if (!s) { missing++; parts.push(id + ":missing"); return; }
    var svgs = s.querySelectorAll("svg"), drawn = 0;
    for (var i = 0; i < svgs.length; i++) {
      var b = svgs[i].getBoundingClientRect();
      if (b.width > 0 && b.height > 0 && svgs[i].querySelectorAll("path,rect,circle,line,polyline,polygon").length > 0) drawn++;
    }
    parts.push(id + ":" + drawn + "/" + svgs.length);
  });
  var p = document.createElement("p");
  p.id = "render-check";
  p.className = "meta";
  p.setAttribute("data-status", missing ? "incomplete" : "ok");
  p.textContent = "render check: " + parts.join(" ");
  document.body.appendChild(p);
})();
)JS";

}  // namespace

std::string render_html(const Report& r) {
  const auto& d = r.data;
  std::ostringstream h;
  char when[32] = "";
  const std::time_t now = std::time(nullptr);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  h << "<!DOCTYPE html>\n<html lang=en><head><meta charset=utf-8>\n<meta name=viewport "
       "content=\"width=device-width, "
       "initial-scale=1\">\n<title>flume report: "
    << xml_escape(d.record.name) << "</title>\n<style>" << kStyle << "</style></head>\n<body>\n";
  h << "<h1>Campaign report: " << xml_escape(d.record.name) << "</h1>\n<p class=meta>"
    << (d.model.empty() ? "scene " + xml_escape(d.scene)
                        : "analytic model <b>" + xml_escape(d.model) + "</b>")
    << " &middot; " << xml_escape(d.design_type) << " design, " << d.rows.size() << " design points";
  if (d.is_saltelli()) h << " (base size N = " << d.saltelli_base_size << ")";
  h << " &middot; parameters: ";
  for (std::size_t i = 0; i < d.parameters.size(); ++i)
    h << (i ? ", " : "") << xml_escape(d.parameters[i].path);
  h << "<br>store " << xml_escape(d.db_file) << " &middot; campaign run by flume "
    << xml_escape(d.record.code_version) << " &middot; report by flume " << build_info::version() << " ("
    << xml_escape(build_info::commit()) << ") on " << when << " &middot; confidence "
    << pct(r.options.stats.confidence) << "</p>\n";
  if (d.model == "debris")
    h << "<p class=warn><b>Synthetic debris model:</b> these runs come from the analytic stand-in `flume "
         "model "
         "debris`, not from the solver; the numbers exercise the report, they are not predictions.</p>\n";
  h << "<nav><a href=#runs>Runs</a><a href=#debris>Debris spreading</a><a href=#metrics>Metrics</a>"
       "<a href=#sensitivity>Sensitivity</a><a href=#surrogates>Surrogates</a><a href=#convergence>Convergence</a>"
       "</nav>\n";
  runs_section(h, r);
  debris_section(h, r);
  metrics_section(h, r);
  sensitivity_section(h, r);
  surrogates_section(h, r);
  convergence_section(h, r);
  h << "<script>" << kCheckScript << "</script>\n</body></html>\n";
  return h.str();
}

}  // namespace flume::report
