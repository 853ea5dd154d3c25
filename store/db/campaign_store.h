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
// Views: run_results (one row per run, its parameters and its metrics as a JSON object) and, per campaign,
// "results_<campaign>" with one column per parameter and per metric.
#pragma once
#include <cstdint>
#include <map>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

struct sqlite3;

namespace flume::store {

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

  // Opens (and for a new file creates) the store. Throws flume::InputError naming the file for a file that
  // is not a flume store or has another schema version; StoreError for SQLite failures.
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
  sqlite3* db_ = nullptr;
  std::map<std::int64_t, std::vector<std::string>> known_metrics_;  // per campaign, to refresh views lazily
};

}  // namespace flume::store
