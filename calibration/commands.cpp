#include "calibration/commands.h"

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "calibration/calibrate.h"
#include "calibration/records.h"
#include "calibration/spec.h"
#include "common/command.h"
#include "common/errors.h"
#include "store/db/campaign_store.h"
#include "store/h5/run_file.h"

namespace flume::calibration {
namespace {

struct TargetArgs {
  std::string h5, out;
  std::vector<std::string> gauges;
  double noise = 0, from = 0, to = 1e30;
  std::uint64_t seed = 1;
};

int target_main(const TargetArgs& a) {
  const std::string& h5 = a.h5;
  const std::string& out = a.out;
  std::vector<std::string> gauges = a.gauges;
  std::vector<SimRecord> records;
  try {
    if (gauges.empty()) gauges = h5::Reader(h5).list("/gauges");
    for (const auto& g : gauges) records.push_back(read_sim_gauge(h5, g));
  } catch (const std::exception& e) {
    throw InputError(h5, "gauges", e.what());
  }
  if (gauges.empty()) throw InputError(h5, "/gauges", "has no gauge records");
  const double rms = write_target_csv(out, gauges, records, a.noise, a.seed, a.from, a.to);
  std::printf("wrote %s: %zu gauge(s), noise sigma %g m (seed %llu), noise RMS %.6g m\n", out.c_str(),
              gauges.size(), a.noise, static_cast<unsigned long long>(a.seed), rms);
  return kExitOk;
}

int history_main(const std::string& db_file, const std::string& name) {
  store::CampaignStore db(db_file, true);
  std::printf("calibration,phase,start,seq,run,objective,params\n");
  for (const auto& c : db.campaigns()) {
    if (!name.empty() && c.name != name) continue;
    for (const auto& e : db.evaluations(c.id)) {
      std::string params = e.params_json;
      for (auto& ch : params)
        if (ch == '"') ch = '\'';
      std::printf("%s,%s,%lld,%lld,%lld,%.10g,\"%s\"\n", c.name.c_str(), e.phase.c_str(),
                  static_cast<long long>(e.start), static_cast<long long>(e.seq),
                  static_cast<long long>(e.run), e.value, params.c_str());
    }
  }
  return kExitOk;
}

int calibrate(const std::string& spec_file, const CalibrateOptions& options) {
  if (spec_file.empty()) throw cli::UsageError("SPEC", "is required (the calibration spec, docs/calibration.md)");
  if (options.db_file.empty()) throw cli::UsageError("--db", "is required (the campaign store to keep the runs in)");
  if (options.out_dir.empty()) throw cli::UsageError("--out", "is required (where calibration.json and the plots go)");
  const CalibrationSpec spec = load_calibration_spec(spec_file);
  CalibrationResult result;
  const int code = run_calibration(spec, options, result);
  if (!result.best.empty()) {
    std::printf(
        "%s: objective %.6g m (RMS %.6g m), %d optimizer + %d profile evaluations, %lld run(s) in the store "
        "(%lld run now), status %s\n",
        spec.name.c_str(), result.best_terms.value, result.best_terms.rms_m, result.optimizer_evaluations,
        result.profile_evaluations, static_cast<long long>(result.runs_total),
        static_cast<long long>(result.runs_executed), result.status.c_str());
    for (size_t j = 0; j < spec.parameters.size(); ++j)
      std::printf("  %s = %.6g\n", spec.parameters[j].path.c_str(), result.best[j]);
    std::printf("wrote %s/calibration.json\n", options.out_dir.c_str());
  }
  return code;
}

}  // namespace

void add_calibrate_command(CLI::App& app) {
  // SPEC, --db and --out are checked by calibrate(): `target` and `history` don't take them.
  struct Args {
    std::string spec;
    CalibrateOptions options;
    TargetArgs target;
    std::string history_db, history_name;
  };
  auto a = std::make_shared<Args>();
  app.add_option("SPEC", a->spec, "the calibration spec (docs/calibration.md)");
  app.add_option("--db", a->options.db_file, "the campaign store the runs are kept in (required)");
  app.add_option("--out", a->options.out_dir, "where calibration.json and the plots go (required)");
  app.add_option("--workers", a->options.workers, "runs at a time")->check(CLI::Range(1, 1024));
  cli::on_parse(app, [a] { return calibrate(a->spec, a->options); });

  CLI::App* target = app.add_subcommand("target", "a run's gauge records as a target CSV, with optional noise");
  target->add_option("RESULT", a->target.h5, "the run's result.h5")->required();
  target->add_option("--out", a->target.out, "the CSV to write")->required();
  target->add_option("--gauge", a->target.gauges, "a gauge to take (repeatable; default: every one)")
      ->allow_extra_args(false);
  target->add_option("--noise-m", a->target.noise, "Gaussian noise sigma (m)")->check(CLI::Range(0.0, 1.0));
  target->add_option("--seed", a->target.seed, "the noise's seed")->check(CLI::Range(0.0, 4294967295.0));
  target->add_option("--from", a->target.from, "first time kept (s)")->check(CLI::Range(0.0, 1e6));
  target->add_option("--to", a->target.to, "last time kept (s)")->check(CLI::Range(0.0, 1e6));
  cli::on_parse(*target, [a] { return target_main(a->target); });

  CLI::App* history = app.add_subcommand("history", "the evaluations in the store, as CSV on stdout");
  history->add_option("--db", a->history_db, "the campaign store")->required();
  history->add_option("--name", a->history_name, "only the calibration of this name");
  cli::on_parse(*history, [a] { return history_main(a->history_db, a->history_name); });
}

}  // namespace flume::calibration
