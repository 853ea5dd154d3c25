// `flume campaign run|status|export` and `flume model`: argument parsing and reporting only.
#include "campaigns/commands.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include "campaigns/engine.h"
#include "campaigns/models.h"
#include "campaigns/spec.h"
#include "common/errors.h"
#include "store/db/campaign_store.h"

#ifdef FLUME_HAVE_MPI
#include <mpi.h>
#endif

namespace flume {
namespace {

const char* kUsage =
    "usage:\n"
    "  flume campaign run SPEC.json --db FILE [--workers N]   run or resume a campaign\n"
    "  mpirun -np K flume campaign run SPEC.json --db FILE    rank 0 hands out runs to ranks 1..K-1\n"
    "  flume campaign status --db FILE [--campaign NAME]      counts, failures, throughput, time left\n"
    "  flume campaign export --db FILE --csv OUT [--campaign NAME]   one row per run ('-': stdout)\n";

struct Args {
  std::vector<std::string> positional;
  std::string db, csv, campaign;
  int workers = -1;
};

Args parse_args(int argc, char** argv, int first) {
  Args a;
  for (int i = first; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&](const char* name) -> std::string {
      if (i + 1 >= argc) throw InputError("command line", name, "needs a value");
      return argv[++i];
    };
    if (s == "--db") {
      a.db = value("--db");
    } else if (s == "--csv") {
      a.csv = value("--csv");
    } else if (s == "--campaign") {
      a.campaign = value("--campaign");
    } else if (s == "--workers") {
      const std::string v = value("--workers");
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (*end || n < 0 || n > 4096) throw InputError("command line", "--workers", "must be an integer in [0, 4096] (got '" + v + "')");
      a.workers = static_cast<int>(n);
    } else if (!s.empty() && s[0] == '-') {
      throw InputError("command line", s, "unknown option");
    } else {
      a.positional.push_back(s);
    }
  }
  if (a.db.empty()) throw InputError("command line", "--db", "is required (the campaign database file)");
  return a;
}

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
    if (args.positional.size() != 1) throw InputError("command line", "SPEC", "expected exactly one campaign spec file");
    const campaigns::CampaignSpec spec = campaigns::load_campaign_spec(args.positional[0]);
    campaigns::EngineOptions opt;
    opt.db_file = args.db;
    // Under MPI the other ranks are the workers; rank 0 runs none itself unless asked.
    opt.local_workers = args.workers >= 0 ? args.workers : (size > 1 ? 0 : 1);
    if (size <= 1 && opt.local_workers == 0) throw InputError("command line", "--workers", "must be at least 1 without MPI");
    opt.terminal = isatty(STDERR_FILENO);
    return campaigns::run_campaign(spec, opt, size);
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
#ifdef FLUME_HAVE_MPI
    if (size > 1) campaigns::stop_workers(size);
#endif
    return kExitInvalidInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flume campaign: %s\n", e.what());
#ifdef FLUME_HAVE_MPI
    if (size > 1) MPI_Abort(MPI_COMM_WORLD, kExitInternal);
#endif
    return kExitInternal;
  }
}

std::string hms(double s) {
  if (!(s >= 0) || s > 1e9) return "unknown";
  const long t = static_cast<long>(s + 0.5);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  return buf;
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
  if (args.csv.empty()) throw InputError("command line", "--csv", "is required (an output file, or - for stdout)");
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

int campaign_main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? kExitInvalidInput : kExitOk;
  }
  const std::string sub = argv[1];
  try {
    const Args args = parse_args(argc, argv, 2);
    if (sub == "run") return run_command_main(args);
    if (sub == "status") return status_main(args);
    if (sub == "export") return export_main(args);
    std::fprintf(stderr, "flume campaign: unknown subcommand '%s'\n%s", sub.c_str(), kUsage);
    return kExitInvalidInput;
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return kExitInvalidInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flume campaign %s: %s\n", sub.c_str(), e.what());
    return kExitInternal;
  }
}

int model_main(int argc, char** argv) { return campaigns::model_main(argc, argv); }

}  // namespace flume
