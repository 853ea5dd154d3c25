// The campaign store: one SQLite file per study (WAL mode, one writer, every change of state in one
// transaction). Schema, version 1:
//   meta(key, value)                     schema_version, created_by
//   campaigns(id, name, spec, spec_hash, code_version, design_size, saltelli_base_size, created)
//   parameters(campaign, position, path, sql_type)    one row per campaign parameter, in design order
//   runs(id, campaign, design_index, param_hash, params, status, message, attempts, queued, started,
//        finished, wall_s, steps, particles, peak_rss_mb, host, worker, run_dir, h5_path,
//        "<parameter path>"...)        one typed column per parameter path, REAL or TEXT
//   design_points(campaign, design_index, run)      design rows -> runs (a repeated point is run once)
//   metrics(run, name, value)
//   evaluations(campaign, phase, start, seq, run, params, value, terms)   an optimizer's objective evaluations
//        (calibrations, whose runs are added one at a time as they are evaluated); added to version 1 files
//        when they are opened for writing
//   surrogates(id, campaign, metric, kind, settings, runs, runs_hash, quality, model, created)   fitted
//        surrogates (`flume surrogate fit`): the run ids they were fitted to, their validation and the
//        OpenTURNS model; added to older version 1 files when they are opened for writing, like evaluations
// Views: run_results (one row per run, its parameters and its metrics as a JSON object) and, per campaign,
// "results_<campaign>" with one column per parameter and per metric.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

struct sqlite3;

namespace flume::store {

class WriterLock;

// A failure of the database itself (corrupt file, disk full, locked past the timeout).
class StoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class RunStatus { kPending, kRunning, kOk, kUnstable, kFailed, kTimeout };
const char* to_string(RunStatus s);
std::optional<RunStatus> run_status_from(const std::string& s);

struct CampaignRecord {
  std::int64_t id = 0;
  std::string name;
  std::string spec;       // the spec as given (canonical JSON text)
  std::string spec_hash;  // what resume compares
  std::string code_version;
  std::int64_t design_size = 0;
  std::int64_t saltelli_base_size = 0;
  std::string created;  // ISO 8601 UTC
};

// A parameter value: a number, or a string (a choice among strings such as boundary conditions).
struct ParamValue {
  bool is_text = false;
  double number = 0.0;
  std::string text;
};

struct ParameterColumn {
  std::string path;  // also the column name in `runs`
  bool is_text = false;
};

// One point of the design as the store keeps it.
struct PlannedRun {
  std::int64_t design_index = 0;
  std::string param_hash;
  std::string params_json;  // {"path": value, ...}
  std::vector<ParamValue> values;  // in parameter order
};

// A run handed to a worker: the store has marked it `running`.
struct RunTicket {
  std::int64_t run_id = 0;
  std::int64_t design_index = 0;  // the first design row with this parameter set
  std::int64_t attempt = 0;       // 1 for the first try; more when a dead job's run is redone
};

struct RunOutcome {
  RunStatus status = RunStatus::kFailed;
  std::string message;
  double wall_s = 0.0;
  std::int64_t steps = -1;      // -1: unknown (NULL in the store)
  std::int64_t particles = -1;
  double peak_rss_mb = -1.0;
  std::string host;
  std::string h5_path;  // empty: none written
  std::vector<std::pair<std::string, double>> metrics;
  // Not stored: the run was stopped by SIGTERM/SIGINT before its end (run.json status "killed", exit 130 or
  // 143). It did not finish, so the caller puts it back to pending rather than recording this outcome.
  bool interrupted = false;
};

// A run as the store has it (a calibration looks its points up before running them).
struct StoredRun {
  std::int64_t id = 0;
  std::int64_t design_index = 0;
  RunStatus status = RunStatus::kPending;
  std::string message;
  std::int64_t attempts = 0;
  double wall_s = 0.0;
  std::string run_dir;
  std::string h5_path;
};

// One objective evaluation of an optimizer: `phase` ("optimize", "polish", "profile"), `start` (its
// multi-start index, or the profiled parameter), `seq` (the order within them); the same triple is the same
// evaluation, so replaying a calibration after a restart rewrites rows rather than adding them.
struct Evaluation {
  std::string phase;
  std::int64_t start = 0;
  std::int64_t seq = 0;
  std::int64_t run = 0;     // 0: no run (a failed start-up)
  std::string params_json;  // every free parameter, also those that need no run (a time shift)
  double value = 0.0;
  std::string terms_json;   // the objective's terms
};

// A surrogate of one metric of a campaign (surrogate/): one row per (campaign, metric, kind), replaced when
// it is refitted. The JSON texts and the model are written and read by the surrogate module only.
struct SurrogateRecord {
  std::int64_t id = 0;
  std::int64_t campaign = 0;
  std::string metric;
  std::string kind;           // "chaos" | "kriging"
  std::string settings_json;  // what the fit was asked for (degree, folds, holdout, seed)
  std::string runs_json;      // the ids of the runs it was fitted and validated on
  std::string runs_hash;      // of settings_json + runs_json: an unchanged fit is not redone
  std::string quality_json;   // Q2, predictions against observations, Sobol' indices, exceedance curve
  std::string model;          // the fitted OpenTURNS result (its XML study)
  std::string created;        // ISO 8601 UTC
};

struct StatusSummary {
  std::map<RunStatus, std::int64_t> counts;
  struct Failure {
    std::int64_t design_index;
    RunStatus status;
    std::string message;
  };
  std::vector<Failure> failures;  // runs that ended unstable, failed or timeout
  double mean_wall_s = 0.0;       // of finished runs
  double throughput_per_h = 0.0;  // finished runs per hour over the most recent finishes; 0 if unknown
};

class CampaignStore {
 public:
  static constexpr int kSchemaVersion = 1;

  // Opens (and for a new file creates) the store. Opened for writing, it holds the database's WriterLock
  // (store/db/writer_lock.h) until destroyed: a second writer, through any path to the same file, is refused.
  // Throws flume::InputError naming the file for a file that cannot be opened, is not a flume store, has
  // another schema version or has another writer; StoreError for SQLite failures.
  explicit CampaignStore(const std::string& file, bool read_only = false);
  ~CampaignStore();
  CampaignStore(const CampaignStore&) = delete;
  CampaignStore& operator=(const CampaignStore&) = delete;

  const std::string& file() const { return file_; }

  std::optional<CampaignRecord> find_campaign(const std::string& name);
  std::vector<CampaignRecord> campaigns();

  // In one transaction: the campaign row, its parameter columns and every design point as a pending run.
  // Returns the campaign id.
  std::int64_t create_campaign(const CampaignRecord& campaign, const std::vector<ParameterColumn>& parameters,
                               const std::vector<PlannedRun>& runs);

  // Resume, in one transaction: design points missing from the store (there are none unless the store was
  // edited) are added as pending, and runs left `running` by a dead job go back to `pending`. Finished runs
  // are untouched. Returns the number of runs put back to pending.
  std::int64_t prepare_resume(std::int64_t campaign, const std::vector<PlannedRun>& runs);

  // Marks the next pending run `running` (attempts + 1, started, host, worker) and returns it.
  std::optional<RunTicket> claim_next(std::int64_t campaign, const std::string& host, const std::string& worker);
  // Sets where the run writes (known once claimed).
  void set_run_dir(std::int64_t run_id, const std::string& dir);
  // Puts a claimed run back to pending (the job is stopping before the run ended).
  void release_run(std::int64_t run_id);
  // The end of a run: status, message, cost and metrics in one transaction.
  void record_outcome(std::int64_t run_id, const RunOutcome& outcome);

  // Metrics derived after the run (a study's errors against its reference), added to or replacing the run's
  // own, in one transaction. Non-finite values are not stored.
  void record_metrics(std::int64_t run_id, const std::vector<std::pair<std::string, double>>& metrics);

  // Runs added one at a time (a calibration: the design is not known in advance). add_run adds `run` as
  // pending, as the next design point, unless a run with its parameter hash exists; returns the run's id.
  std::int64_t add_run(std::int64_t campaign, const PlannedRun& run);
  std::optional<StoredRun> find_run(std::int64_t campaign, const std::string& param_hash);
  // Marks that run `running` as claim_next does; it must be pending.
  RunTicket claim_run(std::int64_t run_id, const std::string& host, const std::string& worker);
  void record_evaluation(std::int64_t campaign, const Evaluation& e);
  // Removes the evaluations of `phase` whose start is `from_start` or later (their runs stay).
  void delete_evaluations(std::int64_t campaign, const std::string& phase, std::int64_t from_start);
  std::vector<Evaluation> evaluations(std::int64_t campaign);

  // Writes a surrogate, replacing the one of the same campaign, metric and kind, in one transaction.
  void save_surrogate(const SurrogateRecord& s);
  // The campaign's surrogates (empty for a file written before surrogates existed); `with_model` false leaves
  // `model` empty (the report needs only the quality).
  std::vector<SurrogateRecord> surrogates(std::int64_t campaign, bool with_model = true);
  std::optional<SurrogateRecord> find_surrogate(std::int64_t campaign, const std::string& metric,
                                                const std::string& kind);

  StatusSummary summary(std::int64_t campaign);
  // One row per design point: campaign, design_index, run id, status, message, parameters, metrics, cost.
  void export_csv(std::optional<std::int64_t> campaign, std::ostream& out);
  // PRAGMA integrity_check: "ok" or the problems found.
  std::string integrity_check();

 private:
  void create_schema();
  void check_schema();
  void refresh_results_view(std::int64_t campaign);
  std::string results_select(std::int64_t campaign, std::vector<std::string>* metric_names);

  std::string file_;
  std::unique_ptr<WriterLock> writer_lock_;  // before db_: released after the connection is closed
  sqlite3* db_ = nullptr;
  std::map<std::int64_t, std::vector<std::string>> known_metrics_;  // per campaign, to refresh views lazily
};

}  // namespace flume::store
