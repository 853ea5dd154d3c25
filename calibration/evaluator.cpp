#include "calibration/evaluator.h"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "campaigns/process.h"
#include "campaigns/run_folders.h"
#include "campaigns/spec.h"
#include "common/errors.h"

namespace flume::calibration {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string run_directory(const CalibrationSpec& spec, const std::string& db_file, std::int64_t index) {
  return campaigns::run_folder(campaigns::runs_base_folder(spec.run.output_dir, db_file, spec.name), index);
}

}  // namespace

std::string run_params_json(const CalibrationSpec& spec, const std::vector<double>& run_values) {
  json params = json::object();
  size_t k = 0;
  for (const auto& p : spec.parameters)
    if (p.needs_run) params[p.path] = run_values.at(k++);
  return params.dump();  // keys sorted, numbers in their shortest round-trip form
}

Evaluator::Evaluator(const CalibrationSpec& spec, store::CampaignStore& db, std::int64_t campaign,
                     const std::string& db_file)
    : spec_(spec), db_(db), campaign_(campaign), db_file_(db_file) {
  exe_ = campaigns::self_executable();
  host_ = campaigns::host_name();
}

std::shared_ptr<RunResult> Evaluator::read_back(const store::StoredRun& r) {
  auto out = std::make_shared<RunResult>();
  out->run_id = r.id;
  out->status = r.status;
  out->message = r.message;
  out->run_dir = r.run_dir;
  out->wall_s = r.wall_s;
  if (r.status != store::RunStatus::kOk) return out;
  for (const auto& t : spec_.targets) {
    try {
      out->gauges[t.gauge] = read_sim_gauge(r.h5_path, t.gauge);
    } catch (const std::exception& e) {
      out->status = store::RunStatus::kFailed;
      out->message = std::string("its gauge record cannot be read: ") + e.what();
      out->gauges.clear();
      break;
    }
  }
  return out;
}

std::shared_ptr<const RunResult> Evaluator::run(const std::vector<double>& run_values) {
  const std::string params = run_params_json(spec_, run_values);
  const std::string hash = campaigns::text_hash(params);
  std::int64_t run_id = 0, design_index = 0;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return !in_flight_.count(hash) || stop_; });
    if (stop_) throw Stopped{};
    if (auto it = memo_.find(hash); it != memo_.end()) return it->second;
    auto stored = db_.find_run(campaign_, hash);
    if (stored && stored->status != store::RunStatus::kPending &&
        stored->status != store::RunStatus::kRunning) {
      // Finished by this job or an earlier one: read back, never rerun.
      if (stored->status == store::RunStatus::kOk && !fs::exists(stored->h5_path))
        throw InputError(db_file_, "runs." + std::to_string(stored->id),
                         "the stored run's result " + stored->h5_path +
                             " is gone; restore it, or start over with "
                             "another database or calibration name");
      auto r = read_back(*stored);
      memo_[hash] = r;
      ++reused_;
      return r;
    }
    if (!stored) {
      store::PlannedRun planned;
      planned.params_json = params;
      planned.param_hash = hash;
      for (double v : run_values) planned.values.push_back(store::ParamValue{false, v, ""});
      db_.add_run(campaign_, planned);
      stored = db_.find_run(campaign_, hash);
    }
    const auto ticket = db_.claim_run(stored->id, host_, "calibrate pid " + std::to_string(getpid()));
    run_id = ticket.run_id;
    design_index = ticket.design_index;
    in_flight_.insert(hash);
  }
  std::vector<std::pair<std::string, std::string>> sets = spec_.overrides;
  size_t k = 0;
  for (const auto& p : spec_.parameters)
    if (p.needs_run) sets.emplace_back(p.path, json(run_values[k++]).dump());
  std::shared_ptr<const RunResult> result;
  try {
    result = execute(run_id, design_index, sets);
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    in_flight_.erase(hash);
    done_.notify_all();
    throw;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  in_flight_.erase(hash);
  memo_[hash] = result;
  done_.notify_all();
  return result;
}

std::shared_ptr<const RunResult> Evaluator::execute(
    std::int64_t run_id, std::int64_t design_index,
    const std::vector<std::pair<std::string, std::string>>& sets) {
  campaigns::ChildSpec c;
  c.dir = run_directory(spec_, db_file_, design_index);
  c.time_limit_s = spec_.run.time_limit_s;
  if (spec_.model.empty())
    c.argv = {exe_, "run", spec_.scene, "--out", c.dir, "--threads", std::to_string(spec_.run.threads)};
  else
    c.argv = {exe_, "model", spec_.model, "--out", c.dir};
  for (const auto& [path, value] : sets) c.argv.insert(c.argv.end(), {"--set", path + "=" + value});
  {
    std::lock_guard<std::mutex> lock(mutex_);
    db_.set_run_dir(run_id, c.dir);
  }
  campaigns::Child child = campaigns::start_child(c);
  store::RunOutcome outcome;
  while (!campaigns::poll_child(child, outcome)) {
    if (stop_check_ && stop_check_()) stop_ = true;
    if (stop_) {
      campaigns::kill_child(child);
      std::lock_guard<std::mutex> lock(mutex_);
      db_.release_run(run_id);
      throw Stopped{};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::lock_guard<std::mutex> lock(
      mutex_);  // also serialises the HDF5 reads (the library is not thread-safe)
  if (outcome.interrupted) {  // stopped by SIGTERM/SIGINT, as a job's end stops its runs: redone on resume
    db_.release_run(run_id);
    stop_ = true;
    throw Stopped{};
  }
  db_.record_outcome(run_id, outcome);
  ++executed_;
  store::StoredRun r;
  r.id = run_id;
  r.design_index = design_index;
  r.status = outcome.status;
  r.message = outcome.message;
  r.wall_s = outcome.wall_s;
  r.run_dir = c.dir;
  r.h5_path = outcome.h5_path;
  return read_back(r);
}

}  // namespace flume::calibration
