// The campaign loop. Every change of a run's state is one store transaction made here, on rank 0 only, so a
// job killed at any moment resumes from the store: finished runs stay finished, in-flight ones are redone.
#include "campaigns/engine.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "campaigns/process.h"
#include "campaigns/run_folders.h"
#include "common/duration.h"
#include "common/errors.h"
#include "common/version.h"

#ifdef FLUME_HAVE_MPI
#include <mpi.h>
#endif

namespace flume::campaigns {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

std::atomic<int> g_stop_signal{0};
extern "C" void on_stop_signal(int sig) { g_stop_signal = sig; }


// Progress: a line rewritten in place on a terminal, one plain line per finished run otherwise (logs).
class Progress {
 public:
  Progress(std::int64_t total, std::int64_t done, std::int64_t failed, bool terminal)
      : total_(total), done_(done), failed_(failed), terminal_(terminal), start_(Clock::now()) {}

  void finished(std::int64_t design_index, const store::RunOutcome& o, int running) {
    ++done_;
    ++done_here_;
    if (o.status != store::RunStatus::kOk) ++failed_;
    if (!terminal_) {
      std::fprintf(stdout, "run %lld %s (%.1f s)%s%s | %s\n", static_cast<long long>(design_index),
                   store::to_string(o.status), o.wall_s, o.status == store::RunStatus::kOk ? "" : ": ",
                   o.status == store::RunStatus::kOk ? "" : o.message.c_str(), line(running).c_str());
      std::fflush(stdout);
    } else {
      show(running, true);
    }
  }
  void show(int running, bool force = false) {
    if (!terminal_) return;
    const auto now = Clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    std::fprintf(stderr, "\r%s\033[K", line(running).c_str());
    std::fflush(stderr);
  }
  void end(int running) {
    if (terminal_) {
      show(running, true);
      std::fprintf(stderr, "\n");
    }
  }

 private:
  std::string line(int running) const {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const std::int64_t left = total_ - done_;
    const double eta = done_here_ > 0 ? elapsed / done_here_ * left : -1;
    char buf[256];
    std::snprintf(buf, sizeof buf, "done %lld/%lld  failed %lld  running %d  ETA %s",
                  static_cast<long long>(done_), static_cast<long long>(total_), static_cast<long long>(failed_),
                  running, left == 0 ? "0:00" : hms(eta).c_str());
    return buf;
  }
  std::int64_t total_, done_, failed_, done_here_ = 0;
  bool terminal_;
  Clock::time_point start_, last_{};
};

#ifdef FLUME_HAVE_MPI
enum Tag : int { kTagHello = 1, kTagWork = 2, kTagStop = 3, kTagResult = 4 };

void send_text(const std::string& text, int dest, int tag) {
  MPI_Send(text.data(), static_cast<int>(text.size()), MPI_CHAR, dest, tag, MPI_COMM_WORLD);
}
std::string receive_text(int source, int tag, MPI_Status* status) {
  MPI_Probe(source, tag, MPI_COMM_WORLD, status);
  int n = 0;
  MPI_Get_count(status, MPI_CHAR, &n);
  std::string text(static_cast<size_t>(n), '\0');
  MPI_Recv(text.data(), n, MPI_CHAR, status->MPI_SOURCE, status->MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return text;
}

json outcome_to_json(const store::RunOutcome& o) {
  json m = json::object();
  for (const auto& [k, v] : o.metrics) m[k] = v;
  return {{"status", store::to_string(o.status)}, {"message", o.message}, {"wall_s", o.wall_s},
          {"steps", o.steps}, {"particles", o.particles}, {"peak_rss_mb", o.peak_rss_mb},
          {"host", o.host}, {"h5_path", o.h5_path}, {"metrics", m}, {"interrupted", o.interrupted}};
}
store::RunOutcome outcome_from_json(const json& j) {
  store::RunOutcome o;
  o.status = store::run_status_from(j.at("status").get<std::string>()).value_or(store::RunStatus::kFailed);
  o.message = j.at("message").get<std::string>();
  o.wall_s = j.at("wall_s").get<double>();
  o.steps = j.at("steps").get<std::int64_t>();
  o.particles = j.at("particles").get<std::int64_t>();
  o.peak_rss_mb = j.at("peak_rss_mb").get<double>();
  o.host = j.at("host").get<std::string>();
  o.h5_path = j.at("h5_path").get<std::string>();
  o.interrupted = j.value("interrupted", false);
  for (auto it = j.at("metrics").begin(); it != j.at("metrics").end(); ++it)
    o.metrics.emplace_back(it.key(), it.value().get<double>());
  return o;
}
#endif

}  // namespace

std::vector<store::PlannedRun> plan_runs(const CampaignSpec& spec) {
  std::vector<store::PlannedRun> runs;
  const auto& values = spec.points.values;
  for (size_t k = 0; k < values.size(); ++k) {
    store::PlannedRun r;
    r.design_index = static_cast<std::int64_t>(k);
    json params = json::object();
    for (size_t j = 0; j < spec.parameters.size(); ++j) {
      const auto& p = spec.parameters[j];
      if (!has_value(spec, k, j)) {  // a list design's point that leaves the path alone: NULL in the store
        store::ParamValue none;
        none.number = std::nan("");
        r.values.push_back(none);
        continue;
      }
      const json v = json::parse(value_json(p, values[k][j]));
      params[p.path] = v;
      store::ParamValue pv;
      pv.is_text = v.is_string();
      if (pv.is_text)
        pv.text = v.get<std::string>();
      else
        pv.number = v.get<double>();
      r.values.push_back(pv);
    }
    r.params_json = params.dump();  // keys sorted: the same parameter set always has the same text and hash
    r.param_hash = text_hash(r.params_json);
    runs.push_back(std::move(r));
  }
  return runs;
}

std::vector<std::string> run_command(const CampaignSpec& spec, size_t index, const std::string& exe,
                                     const std::string& out_dir) {
  std::vector<std::string> argv = {exe};
  if (spec.model.empty()) {
    const std::string& scene = spec.listed ? spec.point_scenes.at(index) : spec.scene;
    argv.insert(argv.end(), {"run", scene, "--out", out_dir, "--threads", std::to_string(spec.run.threads)});
    if (spec.run.checkpoint_every_s > 0) {
      char every[32];
      std::snprintf(every, sizeof every, "%.17g", spec.run.checkpoint_every_s);
      argv.insert(argv.end(), {"--checkpoint-every", every});
      // A run left in flight by a killed job goes on from its last checkpoint rather than from t = 0.
      std::error_code ec;
      if (fs::exists(fs::path(out_dir) / "checkpoint.bin", ec)) argv.push_back("--resume");
    }
  } else {
    argv.insert(argv.end(), {"model", spec.model, "--out", out_dir});
  }
  for (const auto& [path, value] : spec.overrides) argv.insert(argv.end(), {"--set", path + "=" + value});
  for (size_t j = 0; j < spec.parameters.size(); ++j) {
    if (!has_value(spec, index, j) || (spec.listed && spec.parameters[j].path == kScenePath)) continue;
    argv.insert(argv.end(), {"--set", spec.parameters[j].path + "=" + value_json(spec.parameters[j], spec.points.values.at(index)[j])});
  }
  return argv;
}

std::string run_directory(const CampaignSpec& spec, const std::string& db_file, size_t index) {
  return run_folder(runs_base_folder(spec.run.output_dir, db_file, spec.name), static_cast<std::int64_t>(index));
}

int run_campaign(const CampaignSpec& spec, const EngineOptions& options, int mpi_size) {
  store::CampaignStore db(options.db_file);  // the writer lock first: a refused job writes nothing anywhere
  // Before a run is registered: a folder that cannot be written stops the job before it starts.
  check_writable_folder(runs_base_folder(spec.run.output_dir, options.db_file, spec.name), spec.file,
                        "run.output_dir");
  const auto planned = plan_runs(spec);
  std::int64_t campaign = 0;
  if (auto existing = db.find_campaign(spec.name)) {
    if (existing->spec_hash != spec.hash)
      throw InputError(spec.file, "name",
                       "campaign '" + spec.name + "' already exists in " + options.db_file +
                           " with a different spec (stored hash " + existing->spec_hash + ", this spec " + spec.hash +
                           "); only run/description may change on resume: use a new name or another database");
    campaign = existing->id;
    const std::int64_t requeued = db.prepare_resume(campaign, planned);
    if (requeued > 0)
      std::fprintf(stdout, "resuming '%s': %lld run(s) left in flight by the previous job will be redone\n",
                   spec.name.c_str(), static_cast<long long>(requeued));
  } else {
    store::CampaignRecord rec;
    rec.name = spec.name;
    rec.spec = spec.canonical;
    rec.spec_hash = spec.hash;
    rec.code_version = build_info::version_and_commit();
    rec.design_size = static_cast<std::int64_t>(planned.size());
    rec.saltelli_base_size = static_cast<std::int64_t>(spec.points.saltelli_base_size);
    std::vector<store::ParameterColumn> cols;
    for (const auto& p : spec.parameters) cols.push_back({p.path, p.distribution.is_text_choice()});
    campaign = db.create_campaign(rec, cols, planned);
  }

  const store::StatusSummary before = db.summary(campaign);
  std::int64_t total = 0, done = 0, failed = 0;
  for (const auto& [st, n] : before.counts) {
    total += n;
    if (st != store::RunStatus::kPending && st != store::RunStatus::kRunning) done += n;
    if (st == store::RunStatus::kUnstable || st == store::RunStatus::kFailed || st == store::RunStatus::kTimeout)
      failed += n;
  }
  std::fprintf(stdout, "campaign '%s': %lld runs, %lld finished, %lld to run (store %s)\n", spec.name.c_str(),
               static_cast<long long>(total), static_cast<long long>(done), static_cast<long long>(total - done),
               options.db_file.c_str());
  std::fflush(stdout);
  Progress progress(total, done, failed, options.terminal);

  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  const std::string exe = self_executable();
  const std::string host = host_name();

  struct Local {
    store::RunTicket ticket;
    Child child;
  };
  std::vector<Local> local;
  bool exhausted = false;  // no pending run left: failed runs are not retried, so none will appear

  auto claim = [&](const std::string& worker, const std::string& where) -> std::optional<store::RunTicket> {
    if (exhausted) return std::nullopt;
    auto t = db.claim_next(campaign, where, worker);
    if (!t) exhausted = true;
    return t;
  };
  // Records a run's end; a run stopped by a signal (the job's end reaching it before the job, a stray kill)
  // goes back to pending instead, up to kMaxInterruptions tries. Returns whether the run is finished.
  auto settle = [&](const store::RunTicket& t, store::RunOutcome& out) {
    constexpr std::int64_t kMaxInterruptions = 3;
    if (out.interrupted && t.attempt < kMaxInterruptions) {
      db.release_run(t.run_id);
      exhausted = false;  // a pending run again, for the next free slot
      return false;
    }
    if (out.interrupted)
      out.message += "; stopped " + std::to_string(t.attempt) + " times, not retried again";
    db.record_outcome(t.run_id, out);
    return true;
  };
  auto child_spec = [&](const store::RunTicket& t) {
    ChildSpec c;
    c.dir = run_directory(spec, options.db_file, static_cast<size_t>(t.design_index));
    c.argv = run_command(spec, static_cast<size_t>(t.design_index), exe, c.dir);
    c.time_limit_s = spec.run.time_limit_s;
    c.memory_limit_mb = spec.run.memory_limit_mb;
    db.set_run_dir(t.run_id, c.dir);
    return c;
  };

#ifdef FLUME_HAVE_MPI
  std::map<int, store::RunTicket> remote;  // rank -> its run
  std::vector<int> idle;
  std::map<int, json> rank_info;  // rank -> {host, pid} from its hello
  int stopped = 0;
#endif
  const int remote_ranks = mpi_size > 1 ? mpi_size - 1 : 0;

  for (;;) {
    bool busy = false;
    if (g_stop_signal) break;
    while (static_cast<int>(local.size()) < options.local_workers) {
      auto t = claim("local slot " + std::to_string(local.size()) + " pid " + std::to_string(getpid()), host);
      if (!t) break;
      Local l{*t, start_child(child_spec(*t))};
      local.push_back(std::move(l));
      busy = true;
    }
    for (size_t i = 0; i < local.size();) {
      store::RunOutcome out;
      if (poll_child(local[i].child, out)) {
        if (!settle(local[i].ticket, out)) {
          local.erase(local.begin() + static_cast<long>(i));
          busy = true;
          continue;
        }
        progress.finished(local[i].ticket.design_index, out, static_cast<int>(local.size()) - 1);
        local.erase(local.begin() + static_cast<long>(i));
        busy = true;
      } else {
        ++i;
      }
    }
#ifdef FLUME_HAVE_MPI
    if (remote_ranks > 0) {
      int flag = 1;
      while (flag) {
        MPI_Status st;
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
        if (!flag) break;
        const std::string text = receive_text(st.MPI_SOURCE, st.MPI_TAG, &st);
        const int rank = st.MPI_SOURCE;
        if (st.MPI_TAG == kTagHello) rank_info[rank] = json::parse(text);
        if (st.MPI_TAG == kTagResult) {
          auto it = remote.find(rank);
          if (it != remote.end()) {
            store::RunOutcome out = outcome_from_json(json::parse(text));
            if (settle(it->second, out))
              progress.finished(it->second.design_index, out,
                                static_cast<int>(local.size() + remote.size()) - 1);
            remote.erase(it);
          }
        }
        idle.push_back(rank);  // a hello or a result: the rank is free
        busy = true;
      }
      for (int rank : idle) {
        const json& info = rank_info[rank];
        const std::string rank_host = info.value("host", host);
        auto t = claim("rank " + std::to_string(rank) + " pid " + std::to_string(info.value("pid", 0LL)), rank_host);
        if (!t) {
          send_text("", rank, kTagStop);
          ++stopped;
          continue;
        }
        json work = {{"run_id", t->run_id}, {"design_index", t->design_index}};
        const ChildSpec c = child_spec(*t);
        work["dir"] = c.dir;
        work["argv"] = std::vector<std::string>(c.argv.begin() + 1, c.argv.end());  // the worker adds its exe
        work["time_limit_s"] = c.time_limit_s;
        work["memory_limit_mb"] = c.memory_limit_mb;
        send_text(work.dump(), rank, kTagWork);
        remote[rank] = *t;
        busy = true;
      }
      idle.clear();
    }
    const bool remote_done = stopped == remote_ranks;
    const bool remote_busy = !remote.empty();
#else
    const bool remote_done = true;
    const bool remote_busy = false;
#endif
    if (exhausted && local.empty() && !remote_busy && remote_done) break;
    progress.show(static_cast<int>(local.size()));
    if (!busy) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }

  if (g_stop_signal) {
    // Stopped from outside (Ctrl-C, the end of a Slurm allocation): in-flight runs go back to pending.
    for (auto& l : local) {
      kill_child(l.child);
      db.release_run(l.ticket.run_id);
    }
#ifdef FLUME_HAVE_MPI
    for (auto& [rank, t] : remote) db.release_run(t.run_id);
#endif
    progress.end(0);
    std::fprintf(stderr, "flume campaign: stopped by signal %d; run the same command again to resume\n",
                 static_cast<int>(g_stop_signal));
#ifdef FLUME_HAVE_MPI
    if (remote_ranks > 0) MPI_Abort(MPI_COMM_WORLD, 128 + g_stop_signal);
#endif
    return 128 + g_stop_signal;
  }
  progress.end(0);
  const store::StatusSummary after = db.summary(campaign);
  auto count = [&](store::RunStatus s) {
    auto it = after.counts.find(s);
    return static_cast<long long>(it == after.counts.end() ? 0 : it->second);
  };
  std::fprintf(stdout, "campaign '%s' finished: ok %lld, unstable %lld, failed %lld, timeout %lld\n", spec.name.c_str(),
               count(store::RunStatus::kOk), count(store::RunStatus::kUnstable), count(store::RunStatus::kFailed),
               count(store::RunStatus::kTimeout));
  return kExitOk;
}

void stop_workers(int mpi_size) {
#ifdef FLUME_HAVE_MPI
  for (int rank = 1; rank < mpi_size; ++rank) {
    MPI_Status st;
    receive_text(rank, kTagHello, &st);
    send_text("", rank, kTagStop);
  }
#else
  (void)mpi_size;
#endif
}

int worker_loop() {
#ifdef FLUME_HAVE_MPI
  const std::string exe = self_executable();
  send_text(json({{"host", host_name()}, {"pid", static_cast<long long>(getpid())}}).dump(), 0, kTagHello);
  for (;;) {
    MPI_Status st;
    const std::string text = receive_text(0, MPI_ANY_TAG, &st);
    if (st.MPI_TAG == kTagStop) break;
    const json work = json::parse(text);
    ChildSpec c;
    c.dir = work.at("dir").get<std::string>();
    c.argv = {exe};
    for (const auto& a : work.at("argv")) c.argv.push_back(a.get<std::string>());
    c.time_limit_s = work.at("time_limit_s").get<double>();
    c.memory_limit_mb = work.at("memory_limit_mb").get<double>();
    store::RunOutcome out;
    try {
      out = run_child(c);
    } catch (const std::exception& e) {
      out.status = store::RunStatus::kFailed;
      out.message = std::string("could not start the run: ") + e.what();
      out.host = host_name();
    }
    send_text(outcome_to_json(out).dump(), 0, kTagResult);
  }
  return kExitOk;
#else
  std::fprintf(stderr, "flume: this build has no MPI support\n");
  return kExitInternal;
#endif
}

}  // namespace flume::campaigns
