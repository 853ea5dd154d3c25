// fork/exec of one run, its time limit, and reading its run.json.
#include "campaigns/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace flume::campaigns {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// The last non-empty line of a log, for a run that died without a run.json.
std::string last_line(const std::string& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  if (last.size() > 400) last = last.substr(0, 400) + "...";
  return last;
}

}  // namespace

std::string self_executable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot read /proc/self/exe: " + ec.message());
  return p.string();
}

std::string host_name() {
  char buf[256] = {0};
  if (gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

Child start_child(const ChildSpec& spec) {
  std::error_code ec;
  // A redone run must not read the previous attempt's run.json; one that resumes keeps its checkpoint.
  const fs::path checkpoint = fs::path(spec.dir) / "checkpoint.bin", aside = spec.dir + ".checkpoint.bin";
  const bool resume = std::find(spec.argv.begin(), spec.argv.end(), "--resume") != spec.argv.end() &&
                      fs::exists(checkpoint, ec);
  if (resume) fs::rename(checkpoint, aside, ec);
  fs::remove_all(spec.dir, ec);
  fs::create_directories(spec.dir, ec);
  if (resume && !ec) fs::rename(aside, checkpoint, ec);
  if (ec) throw std::runtime_error("cannot create run directory " + spec.dir + ": " + ec.message());
  std::vector<char*> args;
  for (const auto& a : spec.argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const std::string out_log = spec.dir + "/stdout.log", err_log = spec.dir + "/stderr.log";
  const pid_t parent = getpid();
  // The run is not part of any MPI job: hide the launcher's variables so a child can never join it.
  std::vector<std::string> env_text;
  for (char** e = environ; *e; ++e) {
    const std::string v = *e;
    if (v.rfind("OMPI_", 0) == 0 || v.rfind("PMIX_", 0) == 0 || v.rfind("PMI_", 0) == 0) continue;
    env_text.push_back(v);
  }
  std::vector<char*> envp;
  for (auto& v : env_text) envp.push_back(const_cast<char*>(v.c_str()));
  envp.push_back(nullptr);

  Child child;
  child.spec = spec;
  child.start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    // Only async-signal-safe calls from here to exec.
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGKILL);  // a killed campaign takes its runs with it
    if (getppid() != parent) _exit(127);
    const int o = open(out_log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = open(err_log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (o >= 0) dup2(o, 1);
    if (e >= 0) dup2(e, 2);
    const int in = open("/dev/null", O_RDONLY);
    if (in >= 0) dup2(in, 0);
    if (spec.memory_limit_mb > 0) {
      rlimit lim;
      lim.rlim_cur = lim.rlim_max = static_cast<rlim_t>(spec.memory_limit_mb * 1024.0 * 1024.0);
      setrlimit(RLIMIT_AS, &lim);
    }
    execve(args[0], args.data(), envp.data());
    const char msg[] = "flume campaign: exec of the run failed\n";
    (void)!write(2, msg, sizeof msg - 1);
    _exit(127);
  }
  setpgid(pid, pid);  // also from the parent, so the group exists before any kill
  child.pid = pid;
  return child;
}

void kill_child(Child& child) {
  if (child.pid <= 0) return;
  kill(-child.pid, SIGKILL);
  kill(child.pid, SIGKILL);
  int status = 0;
  waitpid(child.pid, &status, 0);
  child.pid = -1;
}

bool poll_child(Child& child, store::RunOutcome& out) {
  int status = 0;
  const pid_t r = waitpid(child.pid, &status, WNOHANG);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - child.start).count();
  if (r == 0) {
    if (wall_s > child.spec.time_limit_s && !child.timed_out) {
      child.timed_out = true;
      kill(-child.pid, SIGKILL);  // the whole group: a run that forked helpers leaves none behind
    }
    return false;
  }
  if (r < 0) {
    out = {};
    out.status = store::RunStatus::kFailed;
    out.message = std::string("lost track of the run process: ") + std::strerror(errno);
    out.wall_s = wall_s;
    return true;
  }
  kill(-child.pid, SIGKILL);  // reap any helpers the run left in its group
  out = outcome_from_exit(status, child.timed_out, child.spec.time_limit_s, child.spec.dir, wall_s);
  child.pid = -1;
  return true;
}

store::RunOutcome run_child(const ChildSpec& spec) {
  Child child = start_child(spec);
  store::RunOutcome out;
  while (!poll_child(child, out)) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return out;
}

store::RunOutcome outcome_from_exit(int wait_status, bool timed_out, double time_limit_s, const std::string& dir,
                                    double wall_s) {
  store::RunOutcome out;
  out.status = store::RunStatus::kFailed;
  out.wall_s = wall_s;
  out.host = host_name();

  // run.json, when the run got far enough to write it.
  json run;
  bool have_json = false;
  {
    std::ifstream in(dir + "/run.json");
    if (in) {
      try {
        in >> run;
        have_json = run.is_object();
      } catch (const json::exception&) {
        have_json = false;
      }
    }
  }
  std::string json_status, json_message;
  if (have_json) {
    try {
      if (run.contains("status") && run["status"].is_string()) json_status = run["status"].get<std::string>();
      if (run.contains("message") && run["message"].is_string()) json_message = run["message"].get<std::string>();
      if (run.contains("metrics") && run["metrics"].is_object())
        for (auto it = run["metrics"].begin(); it != run["metrics"].end(); ++it)
          if (it.value().is_number()) out.metrics.emplace_back(it.key(), it.value().get<double>());
      if (run.contains("cost") && run["cost"].is_object()) {
        const json& c = run["cost"];
        if (c.contains("steps") && c["steps"].is_number()) out.steps = c["steps"].get<std::int64_t>();
        if (c.contains("particles") && c["particles"].is_number()) out.particles = c["particles"].get<std::int64_t>();
        if (c.contains("peak_rss_mb") && c["peak_rss_mb"].is_number()) out.peak_rss_mb = c["peak_rss_mb"].get<double>();
        // The run's own clock excludes start-up; the campaign keeps the process's wall time it measured.
      }
    } catch (const json::exception&) {
      // A malformed field is reported through the status below, not thrown.
    }
  }
  std::error_code ec;
  if (fs::exists(dir + "/result.h5", ec)) out.h5_path = dir + "/result.h5";
  const std::string err_tail = last_line(dir + "/stderr.log");
  auto message_or = [&](const std::string& fallback) {
    return !json_message.empty() ? json_message : (!err_tail.empty() ? err_tail : fallback);
  };

  if (timed_out) {
    out.status = store::RunStatus::kTimeout;
    std::ostringstream m;
    m << "exceeded the time limit of " << time_limit_s << " s and was killed";
    out.message = m.str();
    return out;
  }
  // `flume run` stopped by SIGTERM/SIGINT ends cleanly with run.json status "killed" and exit 128 + signal
  // (solver/run.h): not a result, and not the run's fault.
  const int exit_code = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1;
  const int stop_sig = WIFSIGNALED(wait_status) ? WTERMSIG(wait_status) : exit_code > 128 ? exit_code - 128 : 0;
  if (json_status == "killed" || stop_sig == SIGTERM || stop_sig == SIGINT) {
    out.interrupted = true;
    out.message = "stopped by signal " + std::to_string(stop_sig) + " (" + strsignal(stop_sig) + ") before its end";
    if (!json_message.empty()) out.message += ": " + json_message;
    return out;
  }
  if (WIFSIGNALED(wait_status)) {
    const int sig = WTERMSIG(wait_status);
    out.message = "crashed: killed by signal " + std::to_string(sig) + " (" + strsignal(sig) + ")";
    if (sig == SIGKILL) out.message += "; out of memory, or killed from outside";
    if (!err_tail.empty()) out.message += "; stderr: " + err_tail;
    return out;
  }
  const int code = WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : 1;
  switch (code) {
    case 0:
      if (!have_json) {
        out.message = "exited 0 without writing run.json";
      } else if (json_status == "ok") {
        out.status = store::RunStatus::kOk;
        out.message = json_message;
      } else {
        out.message = "exited 0 but run.json says status '" + json_status + "'";
      }
      break;
    case 3:
      out.status = store::RunStatus::kUnstable;
      out.message = message_or("unstable (exit 3)");
      break;
    case 2: out.message = "invalid input: " + message_or("exit 2"); break;
    case 127: out.message = "could not start the run: " + message_or("exec failed"); break;
    default: out.message = "internal error (exit " + std::to_string(code) + "): " + message_or("no message"); break;
  }
  return out;
}

}  // namespace flume::campaigns
