// Runs a campaign against its store: plan the design into the store (or resume it), then hand runs to a local
// pool of child processes and, under mpirun, to the other MPI ranks. Only this process (rank 0) writes.
#pragma once
#include <string>
#include <vector>

#include "campaigns/spec.h"
#include "store/db/campaign_store.h"

namespace flume::campaigns {

struct EngineOptions {
  std::string db_file;
  int local_workers = 1;  // child processes run by this process at once
  bool terminal = false;  // a live progress line instead of one line per finished run
};

// The store's form of the design: one planned run per design point, keyed by the parameter hash.
std::vector<store::PlannedRun> plan_runs(const CampaignSpec& spec);

// The command line of design point `index` (argv[0] is `exe`).
std::vector<std::string> run_command(const CampaignSpec& spec, size_t index, const std::string& exe,
                                     const std::string& out_dir);

// Where design point `index` writes.
std::string run_directory(const CampaignSpec& spec, const std::string& db_file, size_t index);

// Creates or resumes the campaign and runs every pending run. `mpi_size` > 1: ranks 1.. are workers
// (see worker_loop). Returns the process exit code. Throws InputError for a refused spec.
int run_campaign(const CampaignSpec& spec, const EngineOptions& options, int mpi_size);

// An MPI worker rank: asks rank 0 for runs until told to stop.
int worker_loop();
// Rank 0 when the campaign cannot start (a refused spec): releases the waiting workers.
void stop_workers(int mpi_size);

}  // namespace flume::campaigns
