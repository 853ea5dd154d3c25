// The calibration's runs, backed by the campaign store: a point (the values of the parameters that need a
// run) is looked up by its parameter hash first, so a repeated point, in this job or a stopped one before it,
// is read back and never rerun. New points are added to the store as runs, executed as `flume run` (or
// `flume model gauge`) child processes with the run time limit, and recorded. Thread-safe: multi-starts and
// profile points ask from several threads; a point asked for while it runs is waited for, not run twice.
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "calibration/records.h"
#include "calibration/spec.h"
#include "store/db/campaign_store.h"

namespace flume::calibration {

struct RunResult {
  std::int64_t run_id = 0;
  store::RunStatus status = store::RunStatus::kFailed;
  std::string message;
  std::string run_dir;
  double wall_s = 0;
  std::map<std::string, SimRecord> gauges;  // the target gauges, when the run is ok
};

// Thrown out of a run that was stopped (signal or time budget); the run is back to pending in the store.
struct Stopped {};

class Evaluator {
 public:
  Evaluator(const CalibrationSpec& spec, store::CampaignStore& db, std::int64_t campaign,
            const std::string& db_file);

  // The run at these values (one per spec parameter that needs a run, in spec order).
  std::shared_ptr<const RunResult> run(const std::vector<double>& run_values);

  // Locked access to the store for the caller's own writes (evaluations).
  template <typename F>
  void with_store(F&& f) {
    std::lock_guard<std::mutex> lock(mutex_);
    f(db_);
  }

  void request_stop() { stop_ = true; }
  bool stopping() const { return stop_; }
  // Also polled while a run is in flight (a signal must not wait for an hour-long run to end).
  void set_stop_check(std::function<bool()> check) { stop_check_ = std::move(check); }

  std::int64_t runs_executed() const { return executed_; }
  std::int64_t runs_reused() const { return reused_; }  // found finished in the store

 private:
  std::shared_ptr<const RunResult> execute(std::int64_t run_id, std::int64_t design_index,
                                           const std::vector<std::pair<std::string, std::string>>& sets);
  std::shared_ptr<RunResult> read_back(const store::StoredRun& r);

  const CalibrationSpec& spec_;
  store::CampaignStore& db_;
  std::int64_t campaign_;
  std::string db_file_;
  std::string exe_, host_;
  std::mutex mutex_;
  std::condition_variable done_;
  std::map<std::string, std::shared_ptr<const RunResult>> memo_;  // parameter hash -> result
  std::set<std::string> in_flight_;
  std::atomic<bool> stop_{false};
  std::function<bool()> stop_check_;
  std::atomic<std::int64_t> executed_{0}, reused_{0};
};

// The store's JSON and hash of a run's parameter values (sorted keys, shortest round-trip numbers).
std::string run_params_json(const CalibrationSpec& spec, const std::vector<double>& run_values);

}  // namespace flume::calibration
