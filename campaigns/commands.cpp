// `flume campaign run|status|export` and `flume model`: their options and reporting.
#include "campaigns/commands.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include "campaigns/engine.h"
#include "campaigns/models.h"
#include "campaigns/spec.h"
#include "common/command.h"
#include "common/duration.h"
#include "common/errors.h"
#include "store/db/campaign_store.h"

#ifdef FLUME_HAVE_MPI
#include <mpi.h>
#endif

namespace flume {
namespace {

struct Args {
  std::string spec, db, csv, campaign;
  int workers = -1;
};

// Launched by mpirun/srun: the launcher's variables are present.
bool under_mpi_launcher() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMIX_RANK") || std::getenv("PMI_SIZE");
}

int run_command_main(const Args& args) {
  int rank = 0, size = 1;
#ifdef FLUME_HAVE_MPI
  const bool mpi = under_mpi_launcher();
  if (mpi) {
    MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
  }
  struct Finalize {
    bool on;
    ~Finalize() {
      if (on) MPI_Finalize();
    }
  } finalize{mpi};
  if (rank > 0) return campaigns::worker_loop();
#else
  if (under_mpi_launcher() && std::getenv("OMPI_COMM_WORLD_SIZE") && std::string(std::getenv("OMPI_COMM_WORLD_SIZE")) != "1") {
    std::fprintf(stderr, "flume campaign: this flume was built without MPI; run it without mpirun\n");
    return kExitInvalidInput;
  }
#endif
  try {
    const campaigns::CampaignSpec spec = campaigns::load_campaign_spec(args.spec);
    campaigns::EngineOptions opt;
    opt.db_file = args.db;
    // Under MPI the other ranks are the workers; rank 0 runs none itself unless asked.
    opt.local_workers = args.workers >= 0 ? args.workers : (size > 1 ? 0 : 1);
    if (size <= 1 && opt.local_workers == 0) throw cli::UsageError("--workers", "must be at least 1 without MPI");
    opt.terminal = isatty(STDERR_FILENO);
    return campaigns::run_campaign(spec, opt, size);
  } catch (const std::exception& e) {
    // Rank 0's error is reported by the command line (cli/app.cpp); the workers are stopped first.
#ifdef FLUME_HAVE_MPI
    if (size > 1) {
      if (dynamic_cast<const InputError*>(&e) || dynamic_cast<const cli::UsageError*>(&e)) campaigns::stop_workers(size);
      else MPI_Abort(MPI_COMM_WORLD, kExitInternal);
    }
#endif
    throw;
  }
}

int status_main(const Args& args) {
  store::CampaignStore db(args.db, true);
  bool any = false;
  for (const auto& c : db.campaigns()) {
    if (!args.campaign.empty() && c.name != args.campaign) continue;
    any = true;
    const store::StatusSummary s = db.summary(c.id);
    auto n = [&](store::RunStatus st) {
      auto it = s.counts.find(st);
      return static_cast<long long>(it == s.counts.end() ? 0 : it->second);
    };
    std::printf("campaign '%s': %lld runs, created %s, code %s\n", c.name.c_str(), static_cast<long long>(c.design_size),
                c.created.c_str(), c.code_version.c_str());
    std::printf("  ok %lld  unstable %lld  failed %lld  timeout %lld  running %lld  pending %lld\n",
                n(store::RunStatus::kOk), n(store::RunStatus::kUnstable), n(store::RunStatus::kFailed),
                n(store::RunStatus::kTimeout), n(store::RunStatus::kRunning), n(store::RunStatus::kPending));
    const long long left = n(store::RunStatus::kRunning) + n(store::RunStatus::kPending);
    if (s.throughput_per_h > 0) {
      std::printf("  throughput %.1f runs/h (latest finishes), mean run %.1f s, estimated time left %s%s\n",
                  s.throughput_per_h, s.mean_wall_s, hms(left / s.throughput_per_h * 3600.0).c_str(),
                  n(store::RunStatus::kRunning) == 0 && left > 0 ? " (no run in flight: is a job running?)" : "");
    } else {
      std::printf("  throughput unknown (fewer than 2 finished runs)\n");
    }
    const size_t shown = std::min<size_t>(s.failures.size(), 20);
    if (!s.failures.empty()) std::printf("  failures:\n");
    for (size_t i = 0; i < shown; ++i)
      std::printf("    run %lld %s: %s\n", static_cast<long long>(s.failures[i].design_index),
                  store::to_string(s.failures[i].status), s.failures[i].message.c_str());
    if (s.failures.size() > shown) std::printf("    ... and %zu more\n", s.failures.size() - shown);
  }
  if (!any) {
    if (!args.campaign.empty()) throw InputError(args.db, "--campaign", "no campaign named '" + args.campaign + "'");
    std::printf("no campaigns in %s\n", args.db.c_str());
  }
  return kExitOk;
}

int export_main(const Args& args) {
  store::CampaignStore db(args.db, true);
  std::optional<std::int64_t> campaign;
  if (!args.campaign.empty()) {
    auto c = db.find_campaign(args.campaign);
    if (!c) throw InputError(args.db, "--campaign", "no campaign named '" + args.campaign + "'");
    campaign = c->id;
  }
  if (args.csv == "-") {
    db.export_csv(campaign, std::cout);
    return kExitOk;
  }
  const std::string tmp = args.csv + ".part";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(args.csv, "", "cannot write the CSV file");
    db.export_csv(campaign, out);
  }
  if (std::rename(tmp.c_str(), args.csv.c_str()) != 0) throw InputError(args.csv, "", "cannot write the CSV file");
  return kExitOk;
}

}  // namespace

void add_campaign_command(CLI::App& app) {
  auto a = std::make_shared<Args>();
  auto db = [&](CLI::App* sub) {
    sub->add_option("--db", a->db, "the campaign database (SQLite; docs/results.md)")->required();
  };
  auto name = [&](CLI::App* sub) {
    sub->add_option("--campaign", a->campaign, "only the campaign of this name (default: every one)");
  };

  CLI::App* run = app.add_subcommand("run", "run or resume a campaign (under mpirun -np K: rank 0 hands out runs to ranks 1..K-1)");
  run->add_option("SPEC", a->spec, "the campaign spec (docs/campaigns.md)")->required();
  db(run);
  run->add_option("--workers", a->workers, "runs at a time on this machine (default 1; 0 under MPI)")
      ->check(CLI::Range(0, 4096));
  cli::on_parse(*run, [a] { return run_command_main(*a); });

  CLI::App* status = app.add_subcommand("status", "counts, failures, throughput, time left");
  db(status);
  name(status);
  cli::on_parse(*status, [a] { return status_main(*a); });

  CLI::App* exp = app.add_subcommand("export", "one CSV row per run: parameters, status, metrics");
  db(exp);
  exp->add_option("--csv", a->csv, "the CSV file to write ('-': stdout)")->required();
  name(exp);
  cli::on_parse(*exp, [a] { return export_main(*a); });
}

void add_model_command(CLI::App& app) {
  struct ModelArgs {
    std::string model, out;
    std::vector<std::string> sets;
    int threads = 1;
  };
  auto a = std::make_shared<ModelArgs>();
  std::string names;
  for (const auto& n : campaigns::model_names()) names += (names.empty() ? "" : "|") + n;
  app.add_option("MODEL", a->model, names)->required();
  app.add_option("--out", a->out, "the run's folder (run.json)")->required();
  cli::add_set_option(app, a->sets, "a model input, e.g. --set x1=0.5 (repeatable)");
  app.add_option("--threads", a->threads, "accepted for symmetry with `flume run`; the models are serial");
  cli::on_parse(app, [a] {
    std::vector<std::pair<std::string, std::string>> sets;
    for (const auto& s : a->sets) {
      const auto eq = s.find('=');
      if (eq == std::string::npos || eq == 0) throw cli::UsageError("--set", s + ": expected name=value");
      sets.emplace_back(s.substr(0, eq), s.substr(eq + 1));
    }
    const std::string problem = campaigns::check_model_inputs(a->model, sets);
    if (!problem.empty()) throw cli::UsageError("--set", problem);
    return campaigns::run_model(a->model, a->out, sets);
  });
}

}  // namespace flume
