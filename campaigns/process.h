// One run = one child process, so a crash, a hang or an out-of-memory kill is the run's fate, not the
// campaign's. The child is in its own process group (a time-out kills all of it) and dies with its parent.
#pragma once
#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

#include "store/db/campaign_store.h"

namespace flume::campaigns {

struct ChildSpec {
  std::vector<std::string> argv;  // argv[0] is the executable
  std::string dir;                // output directory: run.json, stdout.log, stderr.log
  double time_limit_s = 3600.0;
  double memory_limit_mb = 0.0;  // 0: no limit
};

struct Child {
  pid_t pid = -1;
  ChildSpec spec;
  std::chrono::steady_clock::time_point start;
  bool timed_out = false;
};

// The absolute path of the running executable (/proc/self/exe), which runs each child.
std::string self_executable();
std::string host_name();

// Empties the run directory and starts the child. Throws std::runtime_error when fork/exec setup fails.
Child start_child(const ChildSpec& spec);
// Non-blocking: true once the child has ended, with `out` filled from its exit and run.json. Kills the
// child's process group when it is past its time limit.
bool poll_child(Child& child, store::RunOutcome& out);
// Blocking: starts, waits (enforcing the time limit) and returns the outcome.
store::RunOutcome run_child(const ChildSpec& spec);
// Kills the child's process group now (the campaign is stopping).
void kill_child(Child& child);

// What a run's exit status and run.json say (exposed for tests).
store::RunOutcome outcome_from_exit(int wait_status, bool timed_out, double time_limit_s, const std::string& dir,
                                    double wall_s);

}  // namespace flume::campaigns
