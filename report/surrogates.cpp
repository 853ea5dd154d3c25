#include "report/surrogates.h"

#include <nlohmann/json.hpp>

#include "common/errors.h"
#include "report/html_parts.h"
#include "report/report.h"
#include "store/db/campaign_store.h"

namespace flume::report {
namespace {

using json = nlohmann::json;
namespace plot = flume::plot;
using namespace html;
using plot::xml_escape;

double number_or_nan(const json& v) { return v.is_number() ? v.get<double>() : std::nan(""); }

std::vector<double> numbers(const json& a) {
  std::vector<double> out;
  for (const auto& v : a) out.push_back(number_or_nan(v));
  return out;
}

Estimate estimate(const json& e) {
  return {number_or_nan(e["value"]), {number_or_nan(e["lo"]), number_or_nan(e["hi"])}};
}

SurrogateSummary parse(const store::SurrogateRecord& rec) {
  const json q = json::parse(rec.quality_json);
  SurrogateSummary s;
  s.metric = rec.metric;
  s.kind = rec.kind;
  s.created = rec.created;
  s.n_train = q.at("n_train").get<std::size_t>();
  s.n_holdout = q.at("n_holdout").get<std::size_t>();
  s.folds = q.at("folds").get<std::size_t>();
  s.q2_cv = number_or_nan(q.at("q2_cv"));
  s.q2_holdout = number_or_nan(q.at("q2_holdout"));
  s.cv_observed = numbers(q.at("cv").at("observed"));
  s.cv_predicted = numbers(q.at("cv").at("predicted"));
  s.holdout_observed = numbers(q.at("holdout").at("observed"));
  s.holdout_predicted = numbers(q.at("holdout").at("predicted"));
  s.inputs = q.at("inputs").get<std::vector<std::string>>();
  s.confidence = q.at("confidence").get<double>();
  s.mean = q.at("mean").get<double>();
  s.std = q.at("std").get<double>();
  if (q.contains("degree")) s.degree = q["degree"].get<int>();
  if (q.contains("terms")) s.terms = q["terms"].get<std::size_t>();
  if (q.contains("sobol")) {
    for (const auto& e : q["sobol"]["first"]) s.first.push_back(estimate(e));
    for (const auto& e : q["sobol"]["total"]) s.total.push_back(estimate(e));
  }
  if (q.contains("classifier")) {
    const json& k = q["classifier"];
    const std::size_t held = k.at("holdout_inside").get<std::size_t>() + k.at("holdout_outside").get<std::size_t>();
    std::ostringstream w;
    w << "where " << q.value("given", s.metric) << " exists (" << k.at("inside").get<std::size_t>() << " of "
      << k.at("inside").get<std::size_t>() + k.at("outside").get<std::size_t>()
      << " runs); the classifier of where judges " << fmt(k.at("accuracy_cv").get<double>())
      << " of the runs right cross-validated";
    if (held > 0) w << " and " << fmt(number_or_nan(k.at("accuracy_holdout"))) << " of " << held << " held back";
    w << ", and puts P(exists) at " << fmt(k.at("p_inside").get<double>());
    s.condition = w.str();
  }
  const json& c = q.at("exceedance");
  s.thresholds = numbers(c.at("thresholds"));
  s.p = numbers(c.at("p"));
  s.p_lo = numbers(c.at("lo"));
  s.p_hi = numbers(c.at("hi"));
  s.replicates = c.at("replicates").get<std::size_t>();
  s.mc_size = c.value("mc_size", std::size_t{0});
  s.band_points = c.value("band_points", std::size_t{0});  // absent in fits stored before it was recorded
  return s;
}

void quality_figure(std::ostringstream& h, const SurrogateSummary& s) {
  plot::Figure fig(1, 2, 980, 320);
  auto& a = fig.axes(0, 0);
  a.title("Predicted against observed").xlabel("observed " + s.metric).ylabel("predicted");
  std::vector<double> all = s.cv_observed;
  all.insert(all.end(), s.holdout_observed.begin(), s.holdout_observed.end());
  if (!all.empty()) {
    const auto [lo, hi] = std::minmax_element(all.begin(), all.end());
    a.line({*lo, *hi}, {*lo, *hi}, {.color = kGrey, .dash = plot::Dash::kDashed, .label = "y = x"});
  }
  a.scatter(s.cv_observed, s.cv_predicted,
            {.color = kBlue, .label = std::to_string(s.folds) + "-fold (out of fold)"});
  if (!s.holdout_observed.empty())
    a.scatter(s.holdout_observed, s.holdout_predicted, {.color = kVermillion, .label = "held back"});
  a.legend(plot::Legend::kUpperLeft);
  auto& b = fig.axes(0, 1);
  b.title("Exceedance from the surrogate, " + pct(s.confidence) + " band").xlabel(s.metric).ylabel("P(Y > t)");
  if (!s.thresholds.empty()) {
    bool band = s.replicates >= 2;
    for (std::size_t i = 0; i < s.p_lo.size(); ++i) band = band && std::isfinite(s.p_lo[i]) && std::isfinite(s.p_hi[i]);
    if (band) b.band(s.thresholds, s.p_lo, s.p_hi, {.color = kBlue, .opacity = 0.2, .label = "band"});
    b.line(s.thresholds, s.p, {.color = kBlue, .width = 1.8, .label = "surrogate"});
    b.ylim(0, 1);
    b.legend(plot::Legend::kUpperRight);
  }
  h << svg_or_note(fig);
}

// P(Y > t) at each threshold with its interval, and where the interval comes from. Drawn for thresholds given
// to the fit (--thresholds); the 25 automatic ones are the curve's, shown in the figure only.
void exceedance_table(std::ostringstream& h, const SurrogateSummary& s) {
  if (s.thresholds.empty() || s.thresholds.size() > 12) return;
  const bool kriging = s.kind == "kriging";
  h << "<table class=small><tr><th>P(" << xml_escape(s.metric) << " &gt; t), from the " << xml_escape(s.kind)
    << " on " << s.n_train << " runs</th>";
  for (double t : s.thresholds) h << "<th>t = " << fmt(t) << "</th>";
  h << "</tr><tr><td>P [" << pct(s.confidence) << " interval]</td>";
  for (std::size_t i = 0; i < s.thresholds.size(); ++i)
    h << "<td>" << est({s.p[i], {s.p_lo[i], s.p_hi[i]}}, 3) << "</td>";
  h << "</tr></table>\n<p class=rests>P: the fraction of the " << xml_escape(s.kind) << (kriging ? " mean" : "")
    << "'s outputs above t on " << s.mc_size << " Monte Carlo points of the input law. ";
  if (s.replicates < 2)
    h << "No interval: the fit was stored without replicates (<code>--bootstrap</code> 0).";
  else if (kriging)
    h << "Interval: percentiles of P over " << s.replicates << " conditional realisations of the kriging "
      << "process on one sample of " << (s.band_points ? std::to_string(s.band_points) : std::string("the"))
      << " input points: the surrogate's uncertainty given the runs (it does not hold the solver's own "
         "error, nor the kriging's covariance parameters' uncertainty).";
  else
    h << "Interval: percentiles of P over " << s.replicates << " bootstrap replicates of the runs, each on "
      << (s.band_points ? std::to_string(s.band_points) + " input points" : std::string("input points"))
      << " of its own: the surrogate's and the sampling's uncertainty, given the terms selected.";
  h << "</p>\n";
}

// The sampling estimates of the same metric (Saltelli design: Sobol' indices; otherwise rank correlations),
// to set beside the chaos indices.
const MetricReport* sampling_estimates(const Report& r, const std::string& metric) {
  for (const auto& m : r.metrics)
    if (m.name == metric && (m.sobol || m.correlations)) return &m;
  return nullptr;
}

}  // namespace

std::vector<SurrogateSummary> load_surrogates(const std::string& db_file, std::int64_t campaign) {
  store::CampaignStore db(db_file, /*read_only=*/true);
  std::vector<SurrogateSummary> out;
  for (const auto& rec : db.surrogates(campaign, /*with_model=*/false)) {
    try {
      out.push_back(parse(rec));
    } catch (const json::exception& e) {
      throw InputError(db_file, "surrogates." + rec.metric + "." + rec.kind + ".quality",
                       std::string("is not a surrogate's quality record: ") + e.what());
    }
  }
  return out;
}

void surrogates_section(std::ostringstream& h, const Report& r) {
  h << "<section id=surrogates><h2>Surrogates</h2>\n";
  if (r.surrogates.empty()) {
    h << "<p class=note>No surrogate is stored for this campaign (<code>flume surrogate fit</code> fits "
         "them).</p></section>\n";
    return;
  }
  h << "<p>Surrogates fitted to the campaign's runs by OpenTURNS (docs/surrogates.md): polynomial chaos "
       "(least squares, LARS selection) and kriging. Q2 = 1 - sum (y - y&#770;)&sup2; / sum (y - "
       "y&#772;)&sup2;, over out-of-fold predictions (k-fold) and over runs held back from the fit; 1 is a "
       "perfect predictor. Chaos Sobol' indices come from the expansion's coefficients with bootstrap "
       "intervals; the exceedance curve is the surrogate on a Monte Carlo sample of the inputs, its band the "
       "spread over bootstrap replicates (chaos) or conditional realisations (kriging).</p>\n";
  for (const auto& s : r.surrogates) {
    h << "<div class=metric id=\"s-" << xml_escape(s.metric) << "-" << xml_escape(s.kind) << "\"><h3>"
      << xml_escape(s.metric) << ": " << xml_escape(s.kind) << "</h3>\n<p class=rests>Fitted on " << s.n_train
      << " runs";
    if (s.kind == "chaos") h << ", total degree " << s.degree << ", " << s.terms << " terms kept";
    h << "; stored " << xml_escape(s.created) << ".</p>\n<table class=small><tr><th>Q2 (" << s.folds
      << "-fold)</th><th>Q2 (" << s.n_holdout << " held back)</th><th>mean</th><th>std</th></tr><tr><td>"
      << fmt(s.q2_cv) << "</td><td>" << fmt(s.q2_holdout) << "</td><td>" << fmt(s.mean) << "</td><td>"
      << fmt(s.std) << "</td></tr></table>\n";
    exceedance_table(h, s);
    if (!s.first.empty()) {
      const MetricReport* m = sampling_estimates(r, s.metric);
      h << "<table class=small><tr><th>input</th><th>S (chaos) [" << pct(s.confidence)
        << "]</th><th></th><th>ST (chaos)</th><th></th>";
      if (m) h << (m->sobol ? "<th>S (sampling)</th><th>ST (sampling)</th>" : "<th>Spearman</th><th>PRCC</th>");
      h << "</tr>\n";
      for (std::size_t k = 0; k < s.inputs.size() && k < s.first.size(); ++k) {
        h << "<tr><td>" << xml_escape(s.inputs[k]) << "</td><td>" << est(s.first[k], 3) << "</td><td>"
          << bar(s.first[k].value, kBlue) << "</td><td>" << est(s.total[k], 3) << "</td><td>"
          << bar(s.total[k].value, kOrange) << "</td>";
        if (m) {
          const int j = r.data.parameter_index(s.inputs[k]);
          const auto& a = m->sobol ? m->sobol->first : m->correlations->spearman;
          const auto& b = m->sobol ? m->sobol->total : m->correlations->prcc;
          if (j >= 0 && static_cast<std::size_t>(j) < a.size())
            h << "<td>" << est(a[j], 3) << "</td><td>" << est(b[j], 3) << "</td>";
        }
        h << "</tr>\n";
      }
      h << "</table>\n";
    }
    quality_figure(h, s);
    h << "</div>\n";
  }
  h << "</section>\n";
}

}  // namespace flume::report
