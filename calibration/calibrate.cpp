#include "calibration/calibrate.h"

#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <exception>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <nlopt.hpp>
#include <thread>

#include "calibration/evaluator.h"
#include "calibration/report.h"
#include "campaigns/run_folders.h"
#include "common/duration.h"
#include "common/errors.h"
#include "common/version.h"

namespace flume::calibration {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) { g_signal = sig; }

// The name-to-algorithm table (spec.cpp holds the same names; a name missing here is a programming error).
nlopt::algorithm nlopt_algorithm(const std::string& name) {
  static const std::map<std::string, nlopt::algorithm> table = {
      {"BOBYQA", nlopt::LN_BOBYQA}, {"COBYLA", nlopt::LN_COBYLA},   {"NELDERMEAD", nlopt::LN_NELDERMEAD},
      {"SBPLX", nlopt::LN_SBPLX},   {"CRS2_LM", nlopt::GN_CRS2_LM}, {"DIRECT_L", nlopt::GN_DIRECT_L},
      {"ISRES", nlopt::GN_ISRES},   {"MLSL", nlopt::G_MLSL_LDS}};
  return table.at(name);
}

std::string result_name(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS:
      return "success";
    case nlopt::STOPVAL_REACHED:
      return "stopval reached";
    case nlopt::FTOL_REACHED:
      return "ftol reached";
    case nlopt::XTOL_REACHED:
      return "xtol reached";
    case nlopt::MAXEVAL_REACHED:
      return "max evaluations reached";
    case nlopt::MAXTIME_REACHED:
      return "max time reached";
    case nlopt::ROUNDOFF_LIMITED:
      return "roundoff limited";
    case nlopt::FORCED_STOP:
      return "stopped";
    default:
      return "failure " + std::to_string(static_cast<int>(r));
  }
}

json terms_json(const ObjectiveTerms& t) {
  auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json g = json::object();
  for (const auto& [name, gt] : t.gauges)
    g[name] = {{"rms_m", gt.rms_m},
               {"peak_error_m", gt.peak_error_m},
               {"arrival_error_s", gt.arrival_error_s},
               {"samples", gt.samples}};
  json j = {{"objective", t.value},
            {"rms_m", num(t.rms_m)},
            {"peak_error_m", num(t.peak_error_m)},
            {"arrival_error_s", num(t.arrival_error_s)},
            {"gauges", g}};
  if (t.failed) j["failed"] = t.failure;
  return j;
}

class Driver {
 public:
  Driver(const CalibrationSpec& spec, const CalibrateOptions& options, Evaluator& evaluator,
         std::int64_t campaign)
      : spec_(spec),
        options_(options),
        evaluator_(evaluator),
        campaign_(campaign),
        objective_(spec.objective, spec.targets, spec.file),
        start_time_(Clock::now()) {
    for (double end : spec.objective.stage_end_s)
      stages_.emplace_back(stage_objective(spec.objective, end), spec.targets, spec.file);
  }

  struct Point {
    ObjectiveTerms terms;  // over the calibration's window
    double optimized = 0;  // what the optimizer sees: the stage's objective in a window continuation
    std::shared_ptr<const RunResult> run;
    double shift = 0;
  };

  // One evaluation at unit coordinates u, recorded in the store as (phase, start, seq). Its terms are
  // always the whole window's (the posterior and the report read them); a stage's own objective is kept
  // beside them.
  Point evaluate(const std::vector<double>& u, const std::string& phase, int start, int seq,
                 const Objective* stage = nullptr) {
    std::vector<double> phys, run_values;
    double shift = 0;
    json params = json::object();
    for (size_t j = 0; j < spec_.parameters.size(); ++j) {
      const auto& p = spec_.parameters[j];
      const double v = p.from_unit(u[j]);
      phys.push_back(v);
      params[p.path] = v;
      if (p.needs_run)
        run_values.push_back(v);
      else
        shift = v;
    }
    Point pt;
    pt.shift = shift;
    pt.run = evaluator_.run(run_values);
    pt.terms = pt.run->status == store::RunStatus::kOk
                   ? objective_.evaluate(pt.run->gauges, shift)
                   : objective_.failure(std::string("run ") + store::to_string(pt.run->status) + ": " +
                                        pt.run->message);
    pt.optimized = pt.terms.value;
    json terms = terms_json(pt.terms);
    if (stage) {
      pt.optimized = pt.run->status == store::RunStatus::kOk ? stage->evaluate(pt.run->gauges, shift).value
                                                             : stage->failure(pt.run->message).value;
      terms["stage"] = {{"window_s", {stage->window_start_s(), stage->window_end_s()}},
                        {"objective", pt.optimized}};
    }
    store::Evaluation e;
    e.phase = phase;
    e.start = start;
    e.seq = seq;
    e.run = pt.run->run_id;
    e.params_json = params.dump();
    e.value = pt.terms.value;
    e.terms_json = terms.dump();
    evaluator_.with_store([&](store::CampaignStore& db) { db.record_evaluation(campaign_, e); });
    report_progress(e, pt);
    return pt;
  }

  // One line per evaluation on stderr, so that an hour-long calibration is seen to move (one fprintf: the
  // lines of parallel starts don't interleave).
  void report_progress(const store::Evaluation& e, const Point& pt) const {
    std::string params;
    const json values = json::parse(e.params_json);  // kept alive through the loop (items() is a view)
    for (const auto& [path, v] : values.items()) {
      char buf[32] = "";
      if (v.is_number()) std::snprintf(buf, sizeof buf, "%.6g", v.get<double>());
      params += (params.empty() ? "" : ", ") + path + " = " + (v.is_number() ? std::string(buf) : v.dump());
    }
    const double wall = std::chrono::duration<double>(Clock::now() - start_time_).count();
    std::fprintf(stderr, "flume calibrate: %s start %d #%d: objective %.6g (%s), run %lld %s, wall %s\n",
                 e.phase.c_str(), static_cast<int>(e.start), static_cast<int>(e.seq), e.value, params.c_str(),
                 static_cast<long long>(pt.run->run_id), store::to_string(pt.run->status), hms(wall).c_str());
  }

  bool past_budget() const {
    return spec_.algorithm.max_time_s > 0 &&
           std::chrono::duration<double>(Clock::now() - start_time_).count() > spec_.algorithm.max_time_s;
  }
  bool must_stop() {
    if (g_signal) evaluator_.request_stop();
    return g_signal || evaluator_.stopping();
  }

  // The objective NLopt calls: stops by throwing forced_stop, keeps any other error to rethrow after.
  struct Context {
    Context(Driver* d, std::string ph, int s, const Objective* st = nullptr)
        : driver(d), phase(std::move(ph)), start(s), stage(st) {}
    Driver* driver;
    std::string phase;
    int start;
    const Objective* stage;  // a window continuation's stage; null: the calibration's window
    int seq = 0;
    std::vector<double> best_u, first_u;
    double best = INFINITY;
    ObjectiveTerms best_terms;
    std::string stop;
    std::exception_ptr error;
  };
  static double nlopt_objective(unsigned n, const double* x, double* grad, void* data) {
    (void)grad;  // derivative-free algorithms only
    auto* c = static_cast<Context*>(data);
    Driver& d = *c->driver;
    if (d.must_stop()) {
      c->stop = "stopped";
      throw nlopt::forced_stop();
    }
    if (d.past_budget()) {
      c->stop = "time budget";
      throw nlopt::forced_stop();
    }
    std::vector<double> u(x, x + n);
    if (c->first_u.empty()) c->first_u = u;
    try {
      const Point p = d.evaluate(u, c->phase, c->start, c->seq++, c->stage);
      if (p.optimized < c->best) {
        c->best = p.optimized;
        c->best_u = u;
        c->best_terms = p.terms;
      }
      return p.optimized;
    } catch (const Stopped&) {
      c->stop = "stopped";
    } catch (...) {
      c->error = std::current_exception();
      c->stop = "error";
    }
    throw nlopt::forced_stop();
  }

  // Runs `algorithm` from u0 in context c; returns NLopt's stop reason unless the context set one.
  void optimize(const std::string& algorithm, int max_evaluations, std::vector<double> u0, Context& c,
                int seed, double initial_step) {
    const unsigned n = static_cast<unsigned>(u0.size());
    nlopt::srand(static_cast<unsigned long>(seed));  // thread-local in NLopt: each start its own sequence
    nlopt::opt opt(nlopt_algorithm(algorithm), n);
    opt.set_lower_bounds(std::vector<double>(n, 0.0));
    opt.set_upper_bounds(std::vector<double>(n, 1.0));
    opt.set_min_objective(&Driver::nlopt_objective, &c);
    opt.set_maxeval(max_evaluations);
    opt.set_xtol_abs(spec_.algorithm.xtol_abs);
    if (spec_.algorithm.ftol_abs > 0) opt.set_ftol_abs(spec_.algorithm.ftol_abs);
    if (is_local_algorithm(algorithm)) opt.set_initial_step(initial_step);
    if (spec_.algorithm.population > 0 && (algorithm == "CRS2_LM" || algorithm == "ISRES"))
      opt.set_population(static_cast<unsigned>(spec_.algorithm.population));
    if (algorithm == "MLSL") {
      nlopt::opt local(nlopt_algorithm(spec_.algorithm.local), n);
      local.set_xtol_abs(spec_.algorithm.xtol_abs);
      if (spec_.algorithm.ftol_abs > 0) local.set_ftol_abs(spec_.algorithm.ftol_abs);
      local.set_initial_step(spec_.algorithm.initial_step);
      opt.set_local_optimizer(local);
    }
    for (auto& v : u0) v = std::clamp(v, 0.0, 1.0);
    double value = 0;
    try {
      const nlopt::result r = opt.optimize(u0, value);
      if (c.stop.empty()) c.stop = result_name(r);
    } catch (const nlopt::forced_stop&) {
      if (c.stop.empty()) c.stop = "stopped";
    } catch (const nlopt::roundoff_limited&) {
      if (c.stop.empty()) c.stop = "roundoff limited";
    }
    if (c.error) std::rethrow_exception(c.error);
  }

  StartResult run_start(int s) {
    StartResult out;
    out.index = s;
    out.from = spec_.starts[static_cast<size_t>(s)];
    std::vector<double> u0;
    for (size_t j = 0; j < spec_.parameters.size(); ++j)
      u0.push_back(spec_.parameters[j].to_unit(out.from[j]));
    // A window continuation's stages (spec.h), each a local fit from the one before's best, the first with
    // the calibration's first step and the later ones with the smaller stage step: they refine, and a
    // large first step would leave the basin the earlier window found.
    double step = spec_.algorithm.initial_step;
    for (size_t k = 0; k < stages_.size(); ++k) {
      Context st(this, stage_phase(k), s, &stages_[k]);
      optimize(spec_.algorithm.name, spec_.algorithm.max_evaluations, u0, st,
               static_cast<int>(spec_.algorithm.seed) + s, step);
      out.stage_evaluations += st.seq;
      if (out.first_u.empty()) out.first_u = st.first_u;
      if (st.stop == "stopped" || st.stop == "time budget") {
        out.stop = st.stop;
        return out;
      }
      if (!st.best_u.empty()) u0 = st.best_u;
      step = spec_.algorithm.stage_step;
    }
    Context c(this, "optimize", s);
    optimize(spec_.algorithm.name, spec_.algorithm.max_evaluations, u0, c,
             static_cast<int>(spec_.algorithm.seed) + s, step);
    out.evaluations = c.seq;
    out.stop = c.stop;
    if (!spec_.algorithm.polish.empty() && !c.best_u.empty() && c.stop != "stopped" &&
        c.stop != "time budget") {
      Context p(this, "polish", s);
      optimize(spec_.algorithm.polish, spec_.algorithm.polish_evaluations, c.best_u, p,
               static_cast<int>(spec_.algorithm.seed) + s, spec_.algorithm.initial_step);
      out.polish_evaluations = p.seq;
      out.stop += "; polish: " + p.stop;
      if (p.stop == "stopped" || p.stop == "time budget") out.stop = p.stop;
      if (p.best < c.best) {
        c.best = p.best;
        c.best_u = p.best_u;
        c.best_terms = p.best_terms;
      }
    }
    out.value = c.best;
    out.terms = c.best_terms;
    out.best_u = c.best_u;
    if (out.first_u.empty()) out.first_u = c.first_u;
    for (size_t j = 0; j < c.best_u.size(); ++j)
      out.best.push_back(spec_.parameters[j].from_unit(c.best_u[j]));
    return out;
  }

  // Runs tasks 0..n-1 on up to `workers` threads; the first error is rethrown here.
  void parallel(int n, const std::function<void(int)>& task) {
    std::atomic<int> next{0};
    std::exception_ptr error;
    std::mutex error_mutex;
    auto worker = [&] {
      for (int i = next++; i < n; i = next++) {
        try {
          task(i);
        } catch (...) {
          std::lock_guard<std::mutex> lock(error_mutex);
          if (!error) error = std::current_exception();
          evaluator_.request_stop();
        }
      }
    };
    const int threads = std::max(1, std::min(options_.workers, n));
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (auto& t : pool) t.join();
    if (error) std::rethrow_exception(error);
  }

  void profiles(CalibrationResult& result) {
    const int m = spec_.profile.points;
    if (m <= 0) return;
    std::vector<double> u_best;
    for (size_t j = 0; j < spec_.parameters.size(); ++j)
      u_best.push_back(spec_.parameters[j].to_unit(result.best[j]));
    struct Task {
      int param, k;
      std::vector<double> u;
    };
    std::vector<Task> tasks;
    for (size_t j = 0; j < spec_.parameters.size(); ++j)
      for (int k = -m; k <= m; ++k) {
        std::vector<double> u = u_best;
        u[j] += k * spec_.profile.span / m;
        if (u[j] < -1e-12 || u[j] > 1 + 1e-12) continue;
        u[j] = std::clamp(u[j], 0.0, 1.0);
        tasks.push_back({static_cast<int>(j), k, u});
      }
    std::vector<Point> points(tasks.size());
    parallel(static_cast<int>(tasks.size()), [&](int i) {
      if (must_stop()) throw Stopped{};
      points[static_cast<size_t>(i)] =
          evaluate(tasks[static_cast<size_t>(i)].u, "profile", tasks[static_cast<size_t>(i)].param,
                   tasks[static_cast<size_t>(i)].k + m);
    });
    result.profile_evaluations = static_cast<int>(tasks.size());
    for (size_t j = 0; j < spec_.parameters.size(); ++j) {
      Profile p;
      p.path = spec_.parameters[j].path;
      for (size_t i = 0; i < tasks.size(); ++i)
        if (tasks[i].param == static_cast<int>(j)) {
          p.values.push_back(spec_.parameters[j].from_unit(tasks[i].u[j]));
          p.objective.push_back(points[i].terms.value);
        }
      const double best = result.best_terms.value;
      if (!p.objective.empty() && best > 0) {
        p.rise_low = (p.objective.front() - best) / best;
        p.rise_high = (p.objective.back() - best) / best;
      }
      result.profiles.push_back(p);
    }
    identifiability(result, tasks, points, u_best);
  }

  template <typename Task>
  void identifiability(CalibrationResult& result, const std::vector<Task>& tasks,
                       const std::vector<Point>& points, const std::vector<double>& u_best) {
    Identifiability& id = result.identifiability;
    const size_t p = spec_.parameters.size();
    const Point best = evaluate_cached(u_best);
    if (best.run->status != store::RunStatus::kOk) {
      id.note = "the best point's run failed";
      return;
    }
    const std::vector<double> r0 = objective_.residuals(best.run->gauges, best.shift);
    const size_t n = r0.size();
    Eigen::MatrixXd jac(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(p));
    for (size_t j = 0; j < p; ++j) {
      // The nearest profile points on each side: a central difference, or one-sided at a bound.
      const Point* lo = nullptr;
      const Point* hi = nullptr;
      double u_lo = u_best[j], u_hi = u_best[j];
      for (size_t i = 0; i < tasks.size(); ++i) {
        if (tasks[i].param != static_cast<int>(j) || tasks[i].k == 0) continue;
        if (tasks[i].k < 0 && (!lo || tasks[i].u[j] > u_lo)) lo = &points[i], u_lo = tasks[i].u[j];
        if (tasks[i].k > 0 && (!hi || tasks[i].u[j] < u_hi)) hi = &points[i], u_hi = tasks[i].u[j];
      }
      auto residual_of = [&](const Point* q) {
        return q ? objective_.residuals(q->run->gauges, q->shift) : r0;
      };
      if ((lo && lo->run->status != store::RunStatus::kOk) ||
          (hi && hi->run->status != store::RunStatus::kOk) || !(u_hi > u_lo)) {
        id.note =
            "a profile run next to the optimum failed, or " + spec_.parameters[j].path + " has no neighbour";
        return;
      }
      const auto a = residual_of(lo), b = residual_of(hi);
      for (size_t i = 0; i < n; ++i)
        jac(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = (b[i] - a[i]) / (u_hi - u_lo);
    }
    const Eigen::MatrixXd jtj = jac.transpose() * jac;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(jtj);
    for (Eigen::Index i = 0; i < eig.eigenvalues().size(); ++i)
      id.eigenvalues.push_back(eig.eigenvalues()(i));
    const double lmin = eig.eigenvalues().minCoeff(), lmax = eig.eigenvalues().maxCoeff();
    id.condition_number = lmin > 0 ? lmax / lmin : INFINITY;
    id.samples = n;
    double ssr = 0;
    for (double r : r0) ssr += r * r;
    const double s2 = n > p ? ssr / static_cast<double>(n - p) : INFINITY;
    if (!(lmin > lmax * 1e-14)) {
      id.note = "J^T J is singular: the records do not determine every parameter";
      id.std_error.assign(p, INFINITY);
      return;
    }
    const Eigen::MatrixXd cov = s2 * jtj.inverse();
    id.correlation.assign(p, std::vector<double>(p, 0.0));
    for (size_t i = 0; i < p; ++i) {
      const auto& par = spec_.parameters[i];
      const double u = par.to_unit(result.best[i]);
      // d(value)/du at the optimum, to express the unit-coordinate error in the parameter's own units.
      const double dv_du = par.scale == Scale::kLog ? par.from_unit(u) * std::log(par.upper / par.lower)
                                                    : par.upper - par.lower;
      id.std_error.push_back(std::sqrt(cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i))) *
                             dv_du);
      for (size_t k = 0; k < p; ++k)
        id.correlation[i][k] = cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) /
                               std::sqrt(cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i)) *
                                         cov(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k)));
    }
    id.available = true;
  }

  // The run at u (in the store by now) and its terms, without recording an evaluation.
  Point evaluate_cached(const std::vector<double>& u) {
    std::vector<double> run_values;
    Point pt;
    for (size_t j = 0; j < spec_.parameters.size(); ++j) {
      const double v = spec_.parameters[j].from_unit(u[j]);
      if (spec_.parameters[j].needs_run)
        run_values.push_back(v);
      else
        pt.shift = v;
    }
    pt.run = evaluator_.run(run_values);
    pt.terms = pt.run->status == store::RunStatus::kOk ? objective_.evaluate(pt.run->gauges, pt.shift)
                                                       : objective_.failure(pt.run->message);
    return pt;
  }

  std::vector<double> to_unit(const std::vector<double>& phys) const {
    std::vector<double> u;
    for (size_t j = 0; j < phys.size(); ++j) u.push_back(spec_.parameters[j].to_unit(phys[j]));
    return u;
  }

  const Objective& objective() const { return objective_; }
  double elapsed_s() const { return std::chrono::duration<double>(Clock::now() - start_time_).count(); }

 private:
  const CalibrationSpec& spec_;
  const CalibrateOptions& options_;
  Evaluator& evaluator_;
  std::int64_t campaign_;
  Objective objective_;
  std::vector<Objective> stages_;  // window continuation (spec.h), in order
  Clock::time_point start_time_;
};

}  // namespace

std::string stage_phase(size_t k) { return "stage-" + std::to_string(k + 1); }

int run_calibration(const CalibrationSpec& spec, const CalibrateOptions& options, CalibrationResult& result) {
  store::CampaignStore db(options.db_file);  // the writer lock first: a refused job writes nothing anywhere
  // Before a run is registered or made: the folders the runs and the results go to must be writable.
  campaigns::check_writable_folder(campaigns::runs_base_folder(spec.run.output_dir, options.db_file, spec.name),
                                   spec.file, "run.output_dir");
  if (!options.out_dir.empty()) campaigns::check_writable_folder(options.out_dir, options.out_dir, "--out");
  std::int64_t campaign = 0;
  if (auto existing = db.find_campaign(spec.name)) {
    if (existing->spec_hash != spec.hash)
      throw InputError(
          spec.file, "name",
          "'" + spec.name + "' is already in " + options.db_file +
              " with another spec (or the scene or a target file changed since); only description, "
              "run, profile and the budgets may change on resume: use a new name or another database");
    campaign = existing->id;
    const std::int64_t requeued = db.prepare_resume(campaign, {});
    std::int64_t finished = 0;
    for (const auto& [st, k] : db.summary(campaign).counts)
      if (st != store::RunStatus::kPending && st != store::RunStatus::kRunning) finished += k;
    std::printf("resuming calibration '%s': %lld finished run(s) in the store%s\n", spec.name.c_str(),
                static_cast<long long>(finished),
                requeued ? (", " + std::to_string(requeued) + " left in flight will be redone").c_str() : "");
  } else {
    store::CampaignRecord rec;
    rec.name = spec.name;
    rec.spec = spec.canonical;
    rec.spec_hash = spec.hash;
    rec.code_version = build_info::version_and_commit();
    std::vector<store::ParameterColumn> cols;
    for (const auto& p : spec.parameters)
      if (p.needs_run) cols.push_back({p.path, false});
    campaign = db.create_campaign(rec, cols, {});
    std::printf("calibration '%s': new in %s\n", spec.name.c_str(), options.db_file.c_str());
  }
  std::fflush(stdout);

  g_signal = 0;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  Evaluator evaluator(spec, db, campaign, options.db_file);
  evaluator.set_stop_check([] { return g_signal != 0; });
  Driver driver(spec, options, evaluator, campaign);

  const int n_starts = static_cast<int>(spec.starts.size());
  result.starts.assign(static_cast<size_t>(n_starts), StartResult{});
  bool interrupted = false;
  try {
    driver.parallel(n_starts, [&](int s) {
      result.starts[static_cast<size_t>(s)] = driver.run_start(s);
      const auto& r = result.starts[static_cast<size_t>(s)];
      std::printf(
          "start %d: objective %.6g after %s%d evaluation(s)%s (%s)\n", s, r.value,
          r.stage_evaluations ? (std::to_string(r.stage_evaluations) + " in stages + ").c_str() : "",
          r.evaluations,
          r.polish_evaluations ? (" + " + std::to_string(r.polish_evaluations) + " polish").c_str() : "",
          r.stop.c_str());
      std::fflush(stdout);
    });
  } catch (const Stopped&) {
    interrupted = true;
  }
  for (const auto& s : result.starts) {
    if (s.stop == "stopped") interrupted = true;
    result.optimizer_evaluations += s.stage_evaluations + s.evaluations + s.polish_evaluations;
  }
  const bool budget = std::any_of(result.starts.begin(), result.starts.end(),
                                  [](const StartResult& s) { return s.stop == "time budget"; });
  result.status = interrupted ? "stopped" : (budget ? "time budget" : "finished");

  // The best start (ties: the lowest index), and which starts reached the same optimum.
  int best = -1;
  for (int s = 0; s < n_starts; ++s)
    if (!result.starts[static_cast<size_t>(s)].best.empty() &&
        (best < 0 ||
         result.starts[static_cast<size_t>(s)].value < result.starts[static_cast<size_t>(best)].value))
      best = s;
  if (best >= 0) {
    result.best_start = best;
    const auto& b = result.starts[static_cast<size_t>(best)];
    result.best = b.best;
    result.best_terms = b.terms;
    result.best_u = b.best_u;
    const auto& ub = b.best_u;
    for (auto& s : result.starts) {
      if (s.best.empty()) continue;
      const auto& us = s.best_u;
      double d = 0;
      for (size_t j = 0; j < us.size(); ++j) d = std::max(d, std::fabs(us[j] - ub[j]));
      s.same_optimum = d <= 0.02;
    }
    try {
      if (!interrupted && result.status == "finished") driver.profiles(result);
      auto bp = driver.evaluate_cached(ub);
      result.best_run = bp.run->run_id;
      result.best_run_dir = bp.run->run_dir;
      for (const auto& [g, rec] : bp.run->gauges) {
        SimRecord shifted = rec;
        for (auto& t : shifted.time) t += bp.shift;  // the fitted record as it was compared
        result.best_records[g] = shifted;
      }
      if (!result.starts[0].first_u.empty()) {
        auto sp = driver.evaluate_cached(result.starts[0].first_u);
        for (const auto& [g, rec] : sp.run->gauges) {
          SimRecord shifted = rec;
          for (auto& t : shifted.time) t += sp.shift;
          result.start_records[g] = shifted;
        }
      }
    } catch (const Stopped&) {
      result.status = "stopped";
    }
  }

  const auto summary = db.summary(campaign);
  for (const auto& [st, k] : summary.counts) result.runs_total += k;
  result.runs_executed = evaluator.runs_executed();
  result.runs_reused = evaluator.runs_reused();
  result.run_wall_s_mean = summary.mean_wall_s;
  std::int64_t finished = 0;
  for (const auto& [st, k] : summary.counts)
    if (st != store::RunStatus::kPending && st != store::RunStatus::kRunning) finished += k;
  result.run_wall_s_total = summary.mean_wall_s * static_cast<double>(finished);
  result.wall_s = driver.elapsed_s();

  if (best >= 0) write_report(spec, options, driver.objective(), result, db.evaluations(campaign));
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  if (result.status == "stopped") {
    std::fprintf(stderr, "flume calibrate: stopped%s; run the same command again to resume\n",
                 g_signal ? (" by signal " + std::to_string(g_signal.load())).c_str() : "");
    return g_signal ? 128 + g_signal : kExitInternal;
  }
  if (result.status == "time budget")
    std::printf("stopped by the time budget (algorithm.max_time_s); run again to continue from the store\n");
  return kExitOk;
}

int evaluate_points(const CalibrationSpec& spec, const std::string& db_file, const std::string& phase,
                    int round, const std::vector<std::vector<double>>& points, int workers) {
  store::CampaignStore db(db_file);  // the writer lock first
  const auto existing = db.find_campaign(spec.name);
  if (!existing) throw InputError(db_file, "--calibration", "no calibration named '" + spec.name + "'");
  // `spec` is the stored one parsed back (parse_stored_calibration_spec): its targets checked against their
  // stored content, its run settings the defaults (the store keeps the identity, not how runs were run).
  db.prepare_resume(existing->id, {});
  // This round replaces any made before with other settings (fewer points would leave stale ones), and the
  // rounds after it, which followed from it.
  db.delete_evaluations(existing->id, phase, round);
  g_signal = 0;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  Evaluator evaluator(spec, db, existing->id, db_file);
  evaluator.set_stop_check([] { return g_signal != 0; });
  CalibrateOptions options;
  options.db_file = db_file;
  options.workers = workers;
  Driver driver(spec, options, evaluator, existing->id);
  bool stopped = false;
  try {
    driver.parallel(static_cast<int>(points.size()), [&](int i) {
      std::vector<double> u;
      for (size_t j = 0; j < spec.parameters.size(); ++j)
        u.push_back(spec.parameters[j].to_unit(points[static_cast<size_t>(i)].at(j)));
      driver.evaluate(u, phase, round, i);
    });
  } catch (const Stopped&) {
    stopped = true;
  }
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  if (stopped || g_signal) {
    std::fprintf(stderr, "flume surrogate posterior: stopped%s; run the same command again to resume\n",
                 g_signal ? (" by signal " + std::to_string(g_signal.load())).c_str() : "");
    return g_signal ? 128 + g_signal : kExitInternal;
  }
  return kExitOk;
}

}  // namespace flume::calibration
