// `flume surrogate`: argument parsing and printing only; the work is in fit.cpp and stored.cpp.
#include "surrogate/commands.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "common/errors.h"
#include "surrogate/adaptive_campaign.h"
#include "surrogate/multilevel_command.h"
#include "surrogate/ot_models.h"
#include "surrogate/posterior.h"
#include "surrogate/posterior_refine.h"
#include "surrogate/series_posterior.h"
#include "surrogate/stored.h"

namespace flume {
namespace {

using json = nlohmann::json;
using surrogate::Kind;

const char* kUsage =
    "usage:\n"
    "  flume surrogate fit --db FILE --campaign NAME --metric M[,M2...] [--kind chaos|kriging|both] [--degree D]\n"
    "        [--folds K] [--holdout N | --validation CAMPAIGN] [--bootstrap B] [--thresholds t1,t2,...] [--seed S]\n"
    "        [--given METRIC] [--force]\n"
    "        runs that lack the metric (or METRIC, such as a gauge's arrival) are left out of the fit, and a\n"
    "        classifier of where it exists is fitted and validated beside it\n"
    "  flume surrogate predict --db FILE --campaign NAME --metric M [--kind chaos|kriging] --at x1=v,x2=v [--at ...]\n"
    "  flume surrogate sobol --db FILE --campaign NAME --metric M      first and total Sobol' indices (chaos)\n"
    "  flume surrogate show --db FILE --campaign NAME                  the stored surrogates and their Q2\n"
    "  flume surrogate adapt SPEC.json --db FILE --metric M [--batch B] [--max-runs N] [--target-q2 Q]\n"
    "        [--threshold T [--target-width W]] [--candidates C] [--folds K] [--workers N] [--seed S]\n"
    "        grow the campaign a batch at a time where the kriging is least sure\n"
    "  flume surrogate multilevel --db FILE --levels HIGH,MID,...,LOW --metric M[,M2...] [--cost S1,S2,...]\n"
    "  flume surrogate multilevel --db FILE --low NAME --high NAME --metric M [--cost-low S --cost-high S]\n"
    "        mean of the highest-fidelity metric from nested campaigns (levels high to low fidelity; costs per\n"
    "        run, default the mean wall times): multi-fidelity Monte Carlo (Peherstorfer et al. 2016) with the\n"
    "        optimal weights and with unit weights, two levels also by Giles' two-level Monte Carlo; each against\n"
    "        high runs alone for the same variance, and the optimal allocation\n"
    "  flume surrogate posterior --db FILE --calibration NAME --noise-m SIGMA [--surrogate series|misfit]\n"
    "        [--neighbourhood D] [--samples N] [--seed S] [--draws K --draws-out SPEC.json [--end-time S]]\n"
    "        [--refine K [--rounds R] [--workers N]]\n"
    "        posterior of a calibration's parameters by MCMC on an emulator of its gauge series (default: the\n"
    "        records of the runs within D noises, default 1, of the best's, by principal components and kriging,\n"
    "        its leave-one-out error added to the noise) or on a kriging of its misfit (--surrogate misfit);\n"
    "        with --draws, a campaign spec of K posterior draws whose runs give the predictive band (flume\n"
    "        gauges --band); with --refine, first R rounds (default 1) that each run K draws of the posterior\n"
    "        as evaluations of the calibration, so that the emulator knows the region the posterior claims\n";

struct Args {
  std::string verb, db, campaign;
  std::vector<std::string> metrics, at;
  std::string kind = "chaos";
  surrogate::FitSettings settings;
  bool force = false;
  std::vector<std::string> positional;
  surrogate::AdaptiveCampaignOptions adapt;
  bool has_threshold = false;
  std::string low, high;
  double cost_low = 0, cost_high = 0;
  std::vector<std::string> levels;
  std::vector<double> costs;
  std::string calibration;
  surrogate::PosteriorSettings posterior;
  bool has_noise = false;
  std::string posterior_surrogate = "series";
  bool has_neighbourhood = false;
  std::string draws_out;
  double end_time = 0;
  surrogate::RefineSettings refine;
};

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

double parse_number(const std::string& option, const std::string& text, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end || !std::isfinite(v) || v < lo || v > hi) {
    char range[96];
    std::snprintf(range, sizeof range, "must be a number in [%g, %g]", lo, hi);
    throw InputError("command line", option, std::string(range) + " (got '" + text + "')");
  }
  return v;
}

std::size_t parse_count(const std::string& option, const std::string& text, double lo, double hi) {
  const double v = parse_number(option, text, lo, hi);
  if (v != std::floor(v)) throw InputError("command line", option, "must be an integer (got '" + text + "')");
  return static_cast<std::size_t>(v);
}

Args parse_args(int argc, char** argv) {
  Args a;
  if (argc < 2) throw InputError("command line", "", "expected a verb: fit, predict, sobol, show, adapt, multilevel or posterior");
  a.verb = argv[1];
  for (int i = 2; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw InputError("command line", s, "needs a value");
      return argv[++i];
    };
    if (s == "--db") {
      a.db = value();
    } else if (s == "--campaign") {
      a.campaign = value();
    } else if (s == "--metric") {
      a.metrics = split(value(), ',');
    } else if (s == "--kind") {
      a.kind = value();
      if (a.kind != "chaos" && a.kind != "kriging" && a.kind != "both")
        throw InputError("command line", "--kind", "must be chaos, kriging or both (got '" + a.kind + "')");
    } else if (s == "--degree") {
      a.settings.degree = static_cast<int>(parse_count(s, value(), 1, 20));
    } else if (s == "--folds") {
      a.settings.folds = parse_count(s, value(), 0, 100000);
    } else if (s == "--holdout") {
      a.settings.holdout = parse_count(s, value(), 0, 1000000);
    } else if (s == "--validation") {
      a.settings.validation = value();
    } else if (s == "--given") {
      a.settings.given = value();
    } else if (s == "--bootstrap") {
      a.settings.bootstrap = parse_count(s, value(), 0, 100000);
    } else if (s == "--seed") {
      a.settings.seed = parse_count(s, value(), 0, 4294967295.0);
    } else if (s == "--thresholds") {
      for (const auto& t : split(value(), ',')) a.settings.thresholds.push_back(parse_number(s, t, -1e300, 1e300));
    } else if (s == "--at") {
      a.at.push_back(value());
    } else if (s == "--force") {
      a.force = true;
    } else if (s == "--batch") {
      a.adapt.adapt.batch = parse_count(s, value(), 1, 10000);
    } else if (s == "--max-runs") {
      a.adapt.max_runs = parse_count(s, value(), 1, 1000000);
    } else if (s == "--target-q2") {
      a.adapt.target_q2 = parse_number(s, value(), 0, 1);
    } else if (s == "--target-width") {
      a.adapt.target_width = parse_number(s, value(), 0, 1);
    } else if (s == "--threshold") {
      a.adapt.adapt.threshold = parse_number(s, value(), -1e300, 1e300);
      a.adapt.adapt.criterion = surrogate::Criterion::kExceedance;
      a.has_threshold = true;
    } else if (s == "--candidates") {
      a.adapt.adapt.candidates = parse_count(s, value(), 10, 1000000);
    } else if (s == "--workers") {
      a.adapt.workers = static_cast<int>(parse_count(s, value(), 1, 4096));
    } else if (s == "--calibration") {
      a.calibration = value();
    } else if (s == "--noise-m") {
      a.posterior.noise_m = parse_number(s, value(), 1e-9, 10);
      a.has_noise = true;
    } else if (s == "--surrogate") {
      a.posterior_surrogate = value();
      if (a.posterior_surrogate != "series" && a.posterior_surrogate != "misfit")
        throw InputError("command line", "--surrogate",
                         "must be series or misfit (got '" + a.posterior_surrogate + "')");
    } else if (s == "--neighbourhood") {
      a.posterior.neighbourhood = parse_number(s, value(), 0, 1e6);
      a.has_neighbourhood = true;
    } else if (s == "--draws") {
      a.posterior.draws = parse_count(s, value(), 2, 10000);
    } else if (s == "--draws-out") {
      a.draws_out = value();
    } else if (s == "--refine") {
      a.refine.points = parse_count(s, value(), 2, 1000);
    } else if (s == "--rounds") {
      a.refine.rounds = static_cast<int>(parse_count(s, value(), 1, 100));
    } else if (s == "--end-time") {
      a.end_time = parse_number(s, value(), 1e-3, 1e4);
    } else if (s == "--samples") {
      a.posterior.samples = parse_count(s, value(), 100, 10000000);
    } else if (s == "--low") {
      a.low = value();
    } else if (s == "--high") {
      a.high = value();
    } else if (s == "--cost-low") {
      a.cost_low = parse_number(s, value(), 1e-9, 1e9);
    } else if (s == "--cost-high") {
      a.cost_high = parse_number(s, value(), 1e-9, 1e9);
    } else if (s == "--levels") {
      a.levels = split(value(), ',');
      if (a.levels.size() < 2) throw InputError("command line", s, "needs at least 2 campaigns, high fidelity first");
    } else if (s == "--cost") {
      for (const auto& t : split(value(), ',')) a.costs.push_back(parse_number(s, t, 1e-9, 1e9));
    } else if (!s.empty() && s[0] != '-') {
      a.positional.push_back(s);
    } else {
      throw InputError("command line", s, "unknown option");
    }
  }
  if (a.db.empty()) throw InputError("command line", "--db", "is required (the campaign database file)");
  if (a.verb != "show" && a.verb != "adapt" && a.positional.size())
    throw InputError("command line", a.positional[0], "unexpected argument");
  if (a.verb != "show" && a.verb != "posterior" && a.metrics.empty()) throw InputError("command line", "--metric", "is required");
  return a;
}

std::vector<Kind> kinds(const Args& a) {
  if (a.kind == "both") return {Kind::kChaos, Kind::kKriging};
  return {*surrogate::kind_from(a.kind)};
}

std::string fmt(const json& v) {
  if (v.is_null()) return "n/a";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v.get<double>());
  return buf;
}

void print_quality(const std::string& metric, const json& q, const char* state) {
  std::printf("%s %s (%s): %zu runs", metric.c_str(), q["kind"].get<std::string>().c_str(), state,
              q["n_train"].get<std::size_t>());
  if (q.contains("degree"))
    std::printf(", degree %d, %zu terms", q["degree"].get<int>(), q["terms"].get<std::size_t>());
  std::printf(", Q2 %zu-fold %s", q["folds"].get<std::size_t>(), fmt(q["q2_cv"]).c_str());
  if (q["n_holdout"].get<std::size_t>() > 0)
    std::printf(", Q2 on %zu held-back runs %s", q["n_holdout"].get<std::size_t>(), fmt(q["q2_holdout"]).c_str());
  std::printf(", mean %.6g, std %.6g%s\n", q["mean"].get<double>(), q["std"].get<double>(),
              q.contains("classifier") ? " (where it exists)" : "");
  if (!q.contains("classifier")) return;
  const json& c = q["classifier"];
  std::printf("  where %s exists: %zu of %zu runs; classifier accuracy cross-validated %s",
              q.value("given", q["metric"].get<std::string>()).c_str(), c["inside"].get<std::size_t>(),
              c["inside"].get<std::size_t>() + c["outside"].get<std::size_t>(), fmt(c["accuracy_cv"]).c_str());
  const std::size_t held = c["holdout_inside"].get<std::size_t>() + c["holdout_outside"].get<std::size_t>();
  if (held > 0) std::printf(", on %zu held-back runs %s", held, fmt(c["accuracy_holdout"]).c_str());
  std::printf(", P(exists) %s under the input law\n", fmt(c["p_inside"]).c_str());
}

int fit(const Args& a) {
  for (const auto& metric : a.metrics)
    for (Kind k : kinds(a)) {
      surrogate::FitSettings s = a.settings;
      s.kind = k;
      const auto r = surrogate::fit_and_store(a.db, a.campaign, metric, s, a.force);
      print_quality(metric, json::parse(r.record.quality_json), r.refitted ? "fitted" : "up to date");
    }
  return kExitOk;
}

int predict(const Args& a) {
  if (a.at.empty()) throw InputError("command line", "--at", "is required: name=value,... for each point");
  if (a.kind == "both") throw InputError("command line", "--kind", "must be chaos or kriging for predict");
  const Kind k = *surrogate::kind_from(a.kind);
  const auto rec = surrogate::stored_surrogate(a.db, a.campaign, a.metrics.front(), k);
  const json q = json::parse(rec.quality_json);
  const auto inputs = q["inputs"].get<std::vector<std::string>>();
  std::vector<std::vector<double>> points;
  for (const auto& at : a.at) {
    std::map<std::string, double> given;
    for (const auto& kv : split(at, ',')) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos) throw InputError("command line", "--at", "expected name=value (got '" + kv + "')");
      given[kv.substr(0, eq)] = parse_number("--at " + kv.substr(0, eq), kv.substr(eq + 1), -1e300, 1e300);
    }
    std::vector<double> p;
    for (const auto& in : inputs) {
      if (!given.count(in)) throw InputError("command line", "--at", "missing input '" + in + "'");
      p.push_back(given[in]);
      given.erase(in);
    }
    if (!given.empty()) throw InputError("command line", "--at", "'" + given.begin()->first + "' is not an input");
    points.push_back(p);
  }
  const surrogate::Surrogate model(k, rec.model);
  const auto y = model.predict(points);
  const auto v = model.variance(points);
  for (const auto& in : inputs) std::printf("%s,", in.c_str());
  std::printf("%s%s\n", a.metrics.front().c_str(), v.empty() ? "" : ",std");
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (double x : points[i]) std::printf("%.10g,", x);
    std::printf("%.10g", y[i]);
    if (!v.empty()) std::printf(",%.6g", std::sqrt(std::max(v[i], 0.0)));
    std::printf("\n");
  }
  return kExitOk;
}

int sobol(const Args& a) {
  for (const auto& metric : a.metrics) {
    const auto rec = surrogate::stored_surrogate(a.db, a.campaign, metric, Kind::kChaos);
    const json q = json::parse(rec.quality_json);
    const auto inputs = q["inputs"].get<std::vector<std::string>>();
    const double conf = q["confidence"].get<double>();
    std::printf("# %s: Sobol' indices from the chaos expansion (%zu runs, Q2 %s), %.0f %% bootstrap intervals "
                "(%zu replicates)\ninput,first,first_lo,first_hi,total,total_lo,total_hi\n",
                metric.c_str(), q["n_train"].get<std::size_t>(), fmt(q["q2_cv"]).c_str(), 100 * conf,
                q["sobol"]["replicates"].get<std::size_t>());
    for (std::size_t j = 0; j < inputs.size(); ++j) {
      const json& f = q["sobol"]["first"][j];
      const json& t = q["sobol"]["total"][j];
      std::printf("%s,%s,%s,%s,%s,%s,%s\n", inputs[j].c_str(), fmt(f["value"]).c_str(), fmt(f["lo"]).c_str(),
                  fmt(f["hi"]).c_str(), fmt(t["value"]).c_str(), fmt(t["lo"]).c_str(), fmt(t["hi"]).c_str());
    }
  }
  return kExitOk;
}

int adapt(Args a) {
  if (a.positional.size() != 1) throw InputError("command line", "SPEC", "expected exactly one campaign spec file");
  if (a.metrics.size() != 1) throw InputError("command line", "--metric", "takes one metric for adapt");
  a.adapt.spec_file = a.positional[0];
  a.adapt.db_file = a.db;
  a.adapt.metric = a.metrics[0];
  a.adapt.folds = a.settings.folds;
  a.adapt.adapt.seed = a.settings.seed;
  if (a.adapt.target_q2 <= 0 && a.adapt.target_width <= 0)
    throw InputError("command line", "--target-q2", "or --target-width is required (when to stop)");
  const auto o = surrogate::run_adaptive_campaign(a.adapt);
  if (o.exit_code > 128) return o.exit_code;
  std::printf("adapt: %s after %zu batch(es), %zu design points\n",
              o.reached ? "target reached" : "run budget spent", o.batches, o.runs);
  return kExitOk;
}

int multilevel(const Args& a) {
  std::vector<std::string> levels = a.levels;
  std::vector<double> costs = a.costs;
  if (!levels.empty() && (!a.low.empty() || !a.high.empty()))
    throw InputError("command line", "--levels", "give either --levels or --low and --high, not both");
  if (levels.empty()) {
    if (a.low.empty() || a.high.empty()) throw InputError("command line", "--levels", "(or --low and --high) is required");
    if (!costs.empty()) throw InputError("command line", "--cost", "goes with --levels; with --low/--high give --cost-low/--cost-high");
    levels = {a.high, a.low};
    costs = {a.cost_high, a.cost_low};
  } else if (a.cost_low > 0 || a.cost_high > 0) {
    throw InputError("command line", "--cost-low", "goes with --low/--high; with --levels give --cost S1,S2,...");
  }
  if (!costs.empty() && costs.size() != levels.size())
    throw InputError("command line", "--cost", "needs one cost per level (" + std::to_string(levels.size()) + ")");
  for (const auto& m : a.metrics) surrogate::print_multilevel(a.db, levels, costs, m, a.settings.confidence);
  return kExitOk;
}

int posterior(Args a) {
  if (a.calibration.empty()) throw InputError("command line", "--calibration", "is required");
  if (!a.has_noise) throw InputError("command line", "--noise-m", "is required (the gauge noise, m)");
  a.posterior.seed = a.settings.seed;
  a.posterior.confidence = a.settings.confidence;
  if (a.posterior.draws > 0 && a.draws_out.empty())
    throw InputError("command line", "--draws-out", "is required with --draws (the campaign spec to write)");
  if (a.posterior.draws == 0 && !a.draws_out.empty())
    throw InputError("command line", "--draws",
                     "is required with --draws-out (how many posterior draws, 2 to 10000)");
  const bool series = a.posterior_surrogate == "series";
  if (!series && a.has_neighbourhood)
    throw InputError("command line", "--neighbourhood", "goes with the series emulator, not --surrogate misfit");
  if (a.refine.points > 0) {
    a.refine.series = series;
    a.refine.workers = a.adapt.workers;
    const int rc = surrogate::refine_posterior(a.db, a.calibration, a.posterior, a.refine);
    if (rc != 0) return rc;
  }
  surrogate::SeriesData series_data;
  surrogate::MisfitData misfit_data;
  if (series)
    series_data = surrogate::load_calibration_series(a.db, a.calibration);
  else
    misfit_data = surrogate::load_calibration_misfit(a.db, a.calibration);
  const surrogate::CalibrationBox& box =
      series ? static_cast<const surrogate::CalibrationBox&>(series_data) : misfit_data;
  double end_time = a.end_time;
  if (a.posterior.draws > 0 && end_time <= 0) {
    const json spec = json::parse(box.spec_json);
    end_time = spec.value("overrides", json::object()).value("solver.end_time", 0.0);
    if (end_time <= 0) throw InputError("command line", "--end-time", "is required: the calibration sets no solver.end_time");
  }
  const auto post = series ? surrogate::series_posterior(series_data, a.posterior)
                           : surrogate::misfit_posterior(misfit_data, a.posterior);
  const double residuals = series ? series_data.n_residuals : misfit_data.n_residuals;
  if (series)
    std::printf(
        "# posterior of '%s': %zu evaluations, %zu near the best fitted by the series emulator (%zu "
        "components, Q2 leave-one-out %.4f, error RMS %.4g m added to the noise), noise %.4g m over %.0f "
        "residuals, %zu MCMC samples (acceptance %.2f)\n",
        a.calibration.c_str(), post.evaluations, post.local, post.components, post.q2, post.emulator_rms,
        a.posterior.noise_m, residuals, a.posterior.samples, post.acceptance);
  else
    std::printf(
        "# posterior of '%s': %zu evaluations, %zu near the best fitted by the misfit surrogate (Q2 "
        "leave-one-out %.4f), noise %.4g m over %.0f residuals, %zu MCMC samples (acceptance %.2f)\n",
        a.calibration.c_str(), post.evaluations, post.local, post.q2, a.posterior.noise_m, residuals,
        a.posterior.samples, post.acceptance);
  // Below 0.5 the surrogate misses more than half the variation among the very evaluations it was fitted
  // to: for the misfit, the curvature that sets the intervals is not the misfit's (docs/surrogates.md, the
  // twins); for the series, its error variance then rivals the series' own and the intervals are mostly it.
  if (!(post.q2 >= 0.5))
    std::printf(
        "# warning: the %s predicts the evaluations it leaves out poorly (Q2 %.3g): the "
        "posterior rests on a fit that does not describe them; evaluate more points near the optimum "
        "(a longer profile) before trusting these intervals\n",
        series ? "series emulator" : "misfit surrogate", post.q2);
  // The likelihood counts every residual as independent noise of sigma: its own test of that assumption.
  const double noise_ratio = surrogate::noise_alone_rms_ratio(residuals, 0.999);
  if (post.best_rms > noise_ratio * a.posterior.noise_m)
    std::printf(
        "# warning: the best misfit, RMS %.4g m, is %.2f times the noise, where noise alone over %.0f "
        "residuals stays below %.3f times (chi-square, 99.9 %%): the residual is not the noise alone "
        "(model error, or the optimizer stopped in a local minimum), so these intervals are too narrow "
        "and need not hold the truth\n",
        post.best_rms, post.best_rms / a.posterior.noise_m, residuals, noise_ratio);
  std::printf("parameter,best,mean,median,lo,hi\n");
  for (const auto& p : post.parameters)
    std::printf("%s,%.6g,%.6g,%.6g,%.6g,%.6g\n", p.name.c_str(), p.best, p.mean, p.median, p.lo, p.hi);
  for (const auto& p : post.parameters)
    if (p.cut)
      std::printf("# warning: the interval of %s reaches the edge of the evaluated neighbourhood, which cuts it: "
                  "evaluate around the optimum more widely (the calibration's profile span)\n", p.name.c_str());
  if (a.posterior.draws > 0) {
    const std::string text = surrogate::predictive_spec(box, post, a.calibration, end_time);
    std::ofstream f(a.draws_out);
    if (!(f << text << "\n")) throw InputError(a.draws_out, "--draws-out", "cannot write the file");
    std::printf("wrote %s: %zu posterior draws (run them with flume campaign run)\n", a.draws_out.c_str(),
                post.draws.size());
  }
  return kExitOk;
}

int show(const Args& a) {
  const auto rec = surrogate::stored_surrogate_list(a.db, a.campaign);
  if (rec.empty()) std::printf("no surrogates stored for this campaign\n");
  for (const auto& r : rec) print_quality(r.metric, json::parse(r.quality_json), r.created.c_str());
  return kExitOk;
}

}  // namespace

int surrogate_main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::fputs(kUsage, stdout);
      return kExitOk;
    }
  }
  return guarded_main("flume surrogate", kUsage, [&] {
    surrogate::detail::quiet_warnings();
    const Args a = parse_args(argc, argv);
    if (a.verb == "fit") return fit(a);
    if (a.verb == "predict") return predict(a);
    if (a.verb == "sobol") return sobol(a);
    if (a.verb == "show") return show(a);
    if (a.verb == "adapt") return adapt(a);
    if (a.verb == "multilevel") return multilevel(a);
    if (a.verb == "posterior") return posterior(a);
    throw InputError("command line", a.verb, "unknown verb (fit, predict, sobol, show, adapt, multilevel, posterior)");
  });
}

}  // namespace flume
