// SQLite campaign store. Every state change is one IMMEDIATE transaction, so a process killed at any
// instant leaves either the old or the new state, never half of it.
#include "store/db/campaign_store.h"

#include <sqlite3.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <set>
#include <sstream>

#include "common/errors.h"
#include "common/number_text.h"
#include "store/db/writer_lock.h"

namespace flume::store {
namespace {

constexpr const char* kEvaluationsTable = R"SQL(
CREATE TABLE IF NOT EXISTS evaluations (
  campaign INTEGER NOT NULL REFERENCES campaigns(id),
  phase TEXT NOT NULL,
  start INTEGER NOT NULL,
  seq INTEGER NOT NULL,
  run INTEGER REFERENCES runs(id),
  params TEXT NOT NULL,
  value REAL,
  terms TEXT,
  PRIMARY KEY (campaign, phase, start, seq));
)SQL";

constexpr const char* kSurrogatesTable = R"SQL(
CREATE TABLE IF NOT EXISTS surrogates (
  id INTEGER PRIMARY KEY,
  campaign INTEGER NOT NULL REFERENCES campaigns(id),
  metric TEXT NOT NULL,
  kind TEXT NOT NULL CHECK (kind IN ('chaos', 'kriging')),
  settings TEXT NOT NULL,
  runs TEXT NOT NULL,
  runs_hash TEXT NOT NULL,
  quality TEXT NOT NULL,
  model BLOB NOT NULL,
  created TEXT NOT NULL,
  UNIQUE (campaign, metric, kind));
)SQL";

constexpr const char* kStatuses[] = {"pending", "running", "ok", "unstable", "failed", "timeout"};

// Columns of `runs` other than the parameters: a parameter path may not reuse one of these names.
const std::set<std::string>& builtin_run_columns() {
  static const std::set<std::string> names = {
      "id",      "campaign", "design_index", "param_hash", "params", "status",      "message",
      "attempts", "queued",  "started",      "finished",   "wall_s", "steps",       "particles",
      "peak_rss_mb", "host", "worker",       "run_dir",    "h5_path"};
  return names;
}

std::string quote_id(const std::string& name) {
  std::string q = "\"";
  for (char c : name) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string quote_text(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
  return q + "'";
}

// "<file>: " for messages: a failure deep in a job must still say which database it was.
std::string file_of(sqlite3* db) {
  const char* f = sqlite3_db_filename(db, "main");
  return f && *f ? std::string(f) + ": " : std::string();
}

class Stmt {
 public:
  Stmt(sqlite3* db, const std::string& sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s_, nullptr) != SQLITE_OK)
      throw StoreError(file_of(db) + "SQL prepare failed: " + sqlite3_errmsg(db) + " in: " + sql);
  }
  ~Stmt() { sqlite3_finalize(s_); }
  Stmt& bind(int i, std::int64_t v) { return check(sqlite3_bind_int64(s_, i, v)); }
  Stmt& bind(int i, int v) { return check(sqlite3_bind_int64(s_, i, v)); }
  Stmt& bind(int i, double v) { return check(sqlite3_bind_double(s_, i, v)); }
  Stmt& bind(int i, const std::string& v) {
    return check(sqlite3_bind_text(s_, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  Stmt& bind_null(int i) { return check(sqlite3_bind_null(s_, i)); }
  Stmt& bind(int i, const ParamValue& v) { return v.is_text ? bind(i, v.text) : bind(i, v.number); }
  // True while there is a row.
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw StoreError(file_of(db_) + "SQL step failed: " + sqlite3_errmsg(db_));
  }
  void run() {
    while (step()) {
    }
  }
  void reset() {
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  std::int64_t i64(int c) const { return sqlite3_column_int64(s_, c); }
  double f64(int c) const { return sqlite3_column_double(s_, c); }
  bool null(int c) const { return sqlite3_column_type(s_, c) == SQLITE_NULL; }
  std::string text(int c) const {
    const unsigned char* t = sqlite3_column_text(s_, c);
    return t ? reinterpret_cast<const char*>(t) : "";
  }
  int columns() const { return sqlite3_column_count(s_); }
  std::string column_name(int c) const { return sqlite3_column_name(s_, c); }
  int type(int c) const { return sqlite3_column_type(s_, c); }

 private:
  Stmt& check(int rc) {
    if (rc != SQLITE_OK) throw StoreError(file_of(db_) + "SQL bind failed: " + sqlite3_errmsg(db_));
    return *this;
  }
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
};

void exec(sqlite3* db, const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    throw StoreError(file_of(db) + "SQL failed: " + msg + " in: " + sql.substr(0, 200));
  }
}

// BEGIN IMMEDIATE takes the write lock up front, so a transaction never fails half-way on a busy lock.
class Transaction {
 public:
  explicit Transaction(sqlite3* db) : db_(db) { exec(db_, "BEGIN IMMEDIATE"); }
  ~Transaction() {
    if (!done_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  void commit() {
    exec(db_, "COMMIT");
    done_ = true;
  }

 private:
  sqlite3* db_;
  bool done_ = false;
};

std::string results_view_name(const std::string& campaign) { return "results_" + campaign; }

// CSV field quoting (RFC 4180).
std::string csv(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string format_number(double v) { return round_trip_text(v); }

}  // namespace

const char* to_string(RunStatus s) { return kStatuses[static_cast<int>(s)]; }

std::optional<RunStatus> run_status_from(const std::string& s) {
  for (int i = 0; i < 6; ++i)
    if (s == kStatuses[i]) return static_cast<RunStatus>(i);
  return std::nullopt;
}

CampaignStore::CampaignStore(const std::string& file, bool read_only) : file_(file) {
  if (!read_only) writer_lock_ = std::make_unique<WriterLock>(file);
  const int flags = read_only ? SQLITE_OPEN_READONLY : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  if (sqlite3_open_v2(file.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw InputError(file, "", "cannot open the campaign database: " + msg);
  }
  // A reader (`campaign status`) may meet the writer mid-transaction: wait rather than fail.
  sqlite3_busy_timeout(db_, 30000);
  try {
    bool empty = false;
    {
      Stmt tables(db_, "SELECT count(*) FROM sqlite_master WHERE type = 'table'");
      tables.step();
      empty = tables.i64(0) == 0;
    }
    if (empty && read_only) throw InputError(file, "", "not a flume campaign database (it has no tables)");
    if (!read_only) {
      exec(db_, "PRAGMA journal_mode = WAL");
      // FULL: a finished run is on disk before the next is handed out, so a lost job never loses results.
      exec(db_, "PRAGMA synchronous = FULL");
      exec(db_, "PRAGMA foreign_keys = ON");
    }
    if (empty) create_schema();
    check_schema();
    // Version 1 files written before calibrations existed lack this table; adding it changes nothing else.
    if (!read_only) exec(db_, kEvaluationsTable);
    // Likewise for files written before surrogates existed.
    if (!read_only) exec(db_, kSurrogatesTable);
  } catch (const StoreError& e) {
    // A folder without room for the -shm file, a file that is not SQLite: about the file given, not internal.
    std::string what = e.what();
    const std::string prefix = file_of(db_);
    if (what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    sqlite3_close(db_);
    db_ = nullptr;
    throw InputError(file, "", "cannot use the campaign database: " + what);
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

CampaignStore::~CampaignStore() {
  if (db_) sqlite3_close(db_);
}

void CampaignStore::create_schema() {
  Transaction t(db_);
  exec(db_, R"SQL(
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS campaigns (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  spec TEXT NOT NULL,
  spec_hash TEXT NOT NULL,
  code_version TEXT NOT NULL,
  design_size INTEGER NOT NULL,
  saltelli_base_size INTEGER NOT NULL DEFAULT 0,
  created TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS parameters (
  campaign INTEGER NOT NULL REFERENCES campaigns(id),
  position INTEGER NOT NULL,
  path TEXT NOT NULL,
  sql_type TEXT NOT NULL CHECK (sql_type IN ('REAL', 'TEXT')),
  PRIMARY KEY (campaign, position));
CREATE TABLE IF NOT EXISTS runs (
  id INTEGER PRIMARY KEY,
  campaign INTEGER NOT NULL REFERENCES campaigns(id),
  design_index INTEGER NOT NULL,
  param_hash TEXT NOT NULL,
  params TEXT NOT NULL,
  status TEXT NOT NULL DEFAULT 'pending'
    CHECK (status IN ('pending', 'running', 'ok', 'unstable', 'failed', 'timeout')),
  message TEXT,
  attempts INTEGER NOT NULL DEFAULT 0,
  queued TEXT NOT NULL,
  started TEXT,
  finished TEXT,
  wall_s REAL,
  steps INTEGER,
  particles INTEGER,
  peak_rss_mb REAL,
  host TEXT,
  worker TEXT,
  run_dir TEXT,
  h5_path TEXT,
  UNIQUE (campaign, param_hash));
CREATE INDEX IF NOT EXISTS runs_by_status ON runs (campaign, status, design_index);
CREATE TABLE IF NOT EXISTS design_points (
  campaign INTEGER NOT NULL REFERENCES campaigns(id),
  design_index INTEGER NOT NULL,
  run INTEGER NOT NULL REFERENCES runs(id),
  PRIMARY KEY (campaign, design_index));
CREATE TABLE IF NOT EXISTS metrics (
  run INTEGER NOT NULL REFERENCES runs(id),
  name TEXT NOT NULL,
  value REAL,
  PRIMARY KEY (run, name));
CREATE VIEW IF NOT EXISTS run_results AS
  SELECT c.name AS campaign_name, r.id AS run, r.design_index, r.status, r.message, r.params,
         (SELECT json_group_object(m.name, m.value) FROM metrics m WHERE m.run = r.id) AS metrics,
         r.wall_s, r.steps, r.particles, r.peak_rss_mb, r.attempts, r.started, r.finished, r.host, r.h5_path
  FROM runs r JOIN campaigns c ON c.id = r.campaign;
)SQL");
  exec(db_, kEvaluationsTable);
  exec(db_, kSurrogatesTable);
  Stmt meta(db_, "INSERT INTO meta (key, value) VALUES ('schema_version', ?1), ('created_by', 'flume')");
  meta.bind(1, std::to_string(kSchemaVersion)).run();
  exec(db_, "PRAGMA user_version = " + std::to_string(kSchemaVersion));
  t.commit();
}

void CampaignStore::check_schema() {
  Stmt has_meta(db_, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'meta'");
  has_meta.step();
  if (has_meta.i64(0) == 0) throw InputError(file_, "", "not a flume campaign database (no meta table)");
  Stmt v(db_, "SELECT value FROM meta WHERE key = 'schema_version'");
  if (!v.step()) throw InputError(file_, "meta.schema_version", "missing: not a flume campaign database");
  const std::string version = v.text(0);
  if (version != std::to_string(kSchemaVersion))
    throw InputError(file_, "meta.schema_version",
                     "is " + version + " but this flume reads version " + std::to_string(kSchemaVersion) +
                         "; use the flume version that wrote it");
}

std::optional<CampaignRecord> CampaignStore::find_campaign(const std::string& name) {
  for (auto& c : campaigns())
    if (c.name == name) return c;
  return std::nullopt;
}

std::vector<CampaignRecord> CampaignStore::campaigns() {
  Stmt s(db_,
         "SELECT id, name, spec, spec_hash, code_version, design_size, saltelli_base_size, created "
         "FROM campaigns ORDER BY id");
  std::vector<CampaignRecord> out;
  while (s.step()) {
    CampaignRecord c;
    c.id = s.i64(0);
    c.name = s.text(1);
    c.spec = s.text(2);
    c.spec_hash = s.text(3);
    c.code_version = s.text(4);
    c.design_size = s.i64(5);
    c.saltelli_base_size = s.i64(6);
    c.created = s.text(7);
    out.push_back(c);
  }
  return out;
}

std::int64_t CampaignStore::create_campaign(const CampaignRecord& campaign,
                                            const std::vector<ParameterColumn>& parameters,
                                            const std::vector<PlannedRun>& runs) {
  Transaction t(db_);
  Stmt ins(db_,
           "INSERT INTO campaigns (name, spec, spec_hash, code_version, design_size, saltelli_base_size, created) "
           "VALUES (?1, ?2, ?3, ?4, ?5, ?6, strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))");
  ins.bind(1, campaign.name).bind(2, campaign.spec).bind(3, campaign.spec_hash).bind(4, campaign.code_version);
  ins.bind(5, campaign.design_size).bind(6, campaign.saltelli_base_size).run();
  const std::int64_t id = sqlite3_last_insert_rowid(db_);

  // Typed parameter columns, shared by the campaigns of this study that use the same path.
  std::set<std::string> existing;
  {
    Stmt cols(db_, "SELECT name FROM pragma_table_info('runs')");
    while (cols.step()) existing.insert(cols.text(0));
  }
  Stmt par(db_, "INSERT INTO parameters (campaign, position, path, sql_type) VALUES (?1, ?2, ?3, ?4)");
  for (size_t i = 0; i < parameters.size(); ++i) {
    const auto& p = parameters[i];
    if (builtin_run_columns().count(p.path))
      throw InputError(file_, "parameters." + std::to_string(i) + ".path",
                       "'" + p.path + "' is the name of a built-in column of runs; rename the parameter");
    const char* type = p.is_text ? "TEXT" : "REAL";
    par.bind(1, id).bind(2, static_cast<std::int64_t>(i)).bind(3, p.path).bind(4, std::string(type)).run();
    par.reset();
    if (!existing.count(p.path)) {
      exec(db_, "ALTER TABLE runs ADD COLUMN " + quote_id(p.path) + " " + type);
      existing.insert(p.path);
    }
  }
  t.commit();
  // The runs go in through the same code as resume (idempotent), in their own transaction: a job killed
  // between the two leaves a campaign whose missing runs the next start adds.
  prepare_resume(id, runs);
  return id;
}

std::int64_t CampaignStore::prepare_resume(std::int64_t campaign, const std::vector<PlannedRun>& runs) {
  std::vector<std::string> paths;
  {
    Stmt p(db_, "SELECT path FROM parameters WHERE campaign = ?1 ORDER BY position");
    p.bind(1, campaign);
    while (p.step()) paths.push_back(p.text(0));
  }
  std::string sql = "INSERT OR IGNORE INTO runs (campaign, design_index, param_hash, params, queued";
  for (const auto& p : paths) sql += ", " + quote_id(p);
  sql += ") VALUES (?1, ?2, ?3, ?4, strftime('%Y-%m-%dT%H:%M:%fZ', 'now')";
  for (size_t i = 0; i < paths.size(); ++i) sql += ", ?" + std::to_string(5 + i);
  sql += ")";

  Transaction t(db_);
  Stmt have(db_, "SELECT count(*) FROM design_points WHERE campaign = ?1");
  have.bind(1, campaign).step();
  if (have.i64(0) < static_cast<std::int64_t>(runs.size())) {
    Stmt ins(db_, sql);
    Stmt find(db_, "SELECT id FROM runs WHERE campaign = ?1 AND param_hash = ?2");
    Stmt point(db_, "INSERT OR IGNORE INTO design_points (campaign, design_index, run) VALUES (?1, ?2, ?3)");
    for (const auto& r : runs) {
      if (r.values.size() != paths.size()) throw StoreError("a planned run has the wrong number of parameters");
      ins.bind(1, campaign).bind(2, r.design_index).bind(3, r.param_hash).bind(4, r.params_json);
      for (size_t i = 0; i < r.values.size(); ++i) ins.bind(static_cast<int>(5 + i), r.values[i]);
      ins.run();
      ins.reset();
      find.bind(1, campaign).bind(2, r.param_hash);
      if (!find.step()) throw StoreError("run vanished after insert");
      const std::int64_t run_id = find.i64(0);
      find.reset();
      point.bind(1, campaign).bind(2, r.design_index).bind(3, run_id).run();
      point.reset();
    }
    // Points appended to the design (`flume surrogate adapt`) count in the campaign's size, as add_run's do.
    Stmt size(db_, "UPDATE campaigns SET design_size = max(design_size, "
                   "(SELECT count(*) FROM design_points WHERE campaign = ?1)) WHERE id = ?1");
    size.bind(1, campaign).run();
  }
  Stmt requeue(db_, "UPDATE runs SET status = 'pending' WHERE campaign = ?1 AND status = 'running'");
  requeue.bind(1, campaign).run();
  const std::int64_t requeued = sqlite3_changes(db_);
  t.commit();
  refresh_results_view(campaign);
  return requeued;
}

std::optional<RunTicket> CampaignStore::claim_next(std::int64_t campaign, const std::string& host,
                                                   const std::string& worker) {
  Transaction t(db_);
  Stmt next(db_,
            "SELECT id, design_index, attempts FROM runs WHERE campaign = ?1 AND status = 'pending' "
            "ORDER BY design_index LIMIT 1");
  next.bind(1, campaign);
  if (!next.step()) return std::nullopt;
  RunTicket ticket{next.i64(0), next.i64(1), next.i64(2) + 1};
  Stmt upd(db_,
           "UPDATE runs SET status = 'running', attempts = ?2, started = strftime('%Y-%m-%dT%H:%M:%fZ', 'now'), "
           "finished = NULL, message = NULL, host = ?3, worker = ?4 WHERE id = ?1");
  upd.bind(1, ticket.run_id).bind(2, ticket.attempt).bind(3, host).bind(4, worker).run();
  t.commit();
  return ticket;
}

void CampaignStore::set_run_dir(std::int64_t run_id, const std::string& dir) {
  Transaction t(db_);
  Stmt s(db_, "UPDATE runs SET run_dir = ?2 WHERE id = ?1");
  s.bind(1, run_id).bind(2, dir).run();
  t.commit();
}

void CampaignStore::release_run(std::int64_t run_id) {
  Transaction t(db_);
  Stmt s(db_, "UPDATE runs SET status = 'pending' WHERE id = ?1 AND status = 'running'");
  s.bind(1, run_id).run();
  t.commit();
}

void CampaignStore::record_outcome(std::int64_t run_id, const RunOutcome& o) {
  if (o.status == RunStatus::kPending || o.status == RunStatus::kRunning)
    throw StoreError("record_outcome needs a final status");
  std::int64_t campaign = 0;
  bool new_metric = false;
  {
    Transaction t(db_);
    Stmt s(db_,
           "UPDATE runs SET status = ?2, message = ?3, finished = strftime('%Y-%m-%dT%H:%M:%fZ', 'now'), "
           "wall_s = ?4, steps = ?5, particles = ?6, peak_rss_mb = ?7, host = ?8, h5_path = ?9 WHERE id = ?1 "
           "RETURNING campaign");
    s.bind(1, run_id).bind(2, std::string(to_string(o.status))).bind(3, o.message).bind(4, o.wall_s);
    o.steps >= 0 ? s.bind(5, o.steps) : s.bind_null(5);
    o.particles >= 0 ? s.bind(6, o.particles) : s.bind_null(6);
    o.peak_rss_mb >= 0 ? s.bind(7, o.peak_rss_mb) : s.bind_null(7);
    s.bind(8, o.host);
    o.h5_path.empty() ? s.bind_null(9) : s.bind(9, o.h5_path);
    if (!s.step()) throw StoreError("no run with id " + std::to_string(run_id));
    campaign = s.i64(0);
    s.run();
    Stmt del(db_, "DELETE FROM metrics WHERE run = ?1");
    del.bind(1, run_id).run();
    Stmt m(db_, "INSERT OR REPLACE INTO metrics (run, name, value) VALUES (?1, ?2, ?3)");
    auto& known = known_metrics_[campaign];
    for (const auto& [name, value] : o.metrics) {
      m.bind(1, run_id).bind(2, name);
      std::isfinite(value) ? m.bind(3, value) : m.bind_null(3);
      m.run();
      m.reset();
      if (std::find(known.begin(), known.end(), name) == known.end()) new_metric = true;
    }
    t.commit();
  }
  if (new_metric) refresh_results_view(campaign);
}

void CampaignStore::record_metrics(std::int64_t run_id, const std::vector<std::pair<std::string, double>>& metrics) {
  std::int64_t campaign = 0;
  bool new_metric = false;
  {
    Transaction t(db_);
    Stmt c(db_, "SELECT campaign FROM runs WHERE id = ?1");
    c.bind(1, run_id);
    if (!c.step()) throw StoreError("no run with id " + std::to_string(run_id));
    campaign = c.i64(0);
    Stmt m(db_, "INSERT OR REPLACE INTO metrics (run, name, value) VALUES (?1, ?2, ?3)");
    auto& known = known_metrics_[campaign];
    for (const auto& [name, value] : metrics) {
      if (!std::isfinite(value)) continue;
      m.bind(1, run_id).bind(2, name).bind(3, value);
      m.run();
      m.reset();
      if (std::find(known.begin(), known.end(), name) == known.end()) new_metric = true;
    }
    t.commit();
  }
  if (new_metric) refresh_results_view(campaign);
}

// The per-campaign wide query: one column per parameter and per metric name seen so far.
std::string CampaignStore::results_select(std::int64_t campaign, std::vector<std::string>* metric_names) {
  std::vector<std::string> paths, metrics;
  Stmt p(db_, "SELECT path FROM parameters WHERE campaign = ?1 ORDER BY position");
  p.bind(1, campaign);
  while (p.step()) paths.push_back(p.text(0));
  Stmt m(db_,
         "SELECT DISTINCT m.name FROM metrics m JOIN runs r ON r.id = m.run WHERE r.campaign = ?1 ORDER BY m.name");
  m.bind(1, campaign);
  while (m.step()) metrics.push_back(m.text(0));
  std::string sql = "SELECT d.design_index AS design_index, r.id AS run, r.status AS status, r.message AS message";
  for (const auto& path : paths) sql += ", r." + quote_id(path) + " AS " + quote_id(path);
  for (const auto& name : metrics)
    sql += ", (SELECT value FROM metrics WHERE run = r.id AND name = " + quote_text(name) + ") AS " + quote_id(name);
  sql += ", r.wall_s AS wall_s, r.steps AS steps, r.particles AS particles, r.peak_rss_mb AS peak_rss_mb, "
         "r.attempts AS attempts, r.host AS host, r.h5_path AS h5_path "
         "FROM design_points d JOIN runs r ON r.id = d.run WHERE d.campaign = " +
         std::to_string(campaign) + " ORDER BY d.design_index";
  if (metric_names) *metric_names = metrics;
  return sql;
}

// The view is rebuilt when a new metric name appears, so its columns follow what the runs report.
void CampaignStore::refresh_results_view(std::int64_t campaign) {
  std::string name;
  {
    Stmt c(db_, "SELECT name FROM campaigns WHERE id = ?1");
    c.bind(1, campaign);
    if (!c.step()) return;
    name = c.text(0);
  }
  std::vector<std::string> metrics;
  const std::string select = results_select(campaign, &metrics);
  Transaction t(db_);
  exec(db_, "DROP VIEW IF EXISTS " + quote_id(results_view_name(name)));
  exec(db_, "CREATE VIEW " + quote_id(results_view_name(name)) + " AS " + select);
  t.commit();
  known_metrics_[campaign] = metrics;
}

std::int64_t CampaignStore::add_run(std::int64_t campaign, const PlannedRun& r) {
  std::vector<std::string> paths;
  {
    Stmt p(db_, "SELECT path FROM parameters WHERE campaign = ?1 ORDER BY position");
    p.bind(1, campaign);
    while (p.step()) paths.push_back(p.text(0));
  }
  if (r.values.size() != paths.size()) throw StoreError("a planned run has the wrong number of parameters");
  Transaction t(db_);
  {
    Stmt find(db_, "SELECT id FROM runs WHERE campaign = ?1 AND param_hash = ?2");
    find.bind(1, campaign).bind(2, r.param_hash);
    if (find.step()) return find.i64(0);  // the transaction rolls back: nothing was changed
  }
  Stmt next(db_, "SELECT coalesce(max(design_index) + 1, 0) FROM design_points WHERE campaign = ?1");
  next.bind(1, campaign).step();
  const std::int64_t index = next.i64(0);
  std::string sql = "INSERT INTO runs (campaign, design_index, param_hash, params, queued";
  for (const auto& p : paths) sql += ", " + quote_id(p);
  sql += ") VALUES (?1, ?2, ?3, ?4, strftime('%Y-%m-%dT%H:%M:%fZ', 'now')";
  for (size_t i = 0; i < paths.size(); ++i) sql += ", ?" + std::to_string(5 + i);
  sql += ")";
  Stmt ins(db_, sql);
  ins.bind(1, campaign).bind(2, index).bind(3, r.param_hash).bind(4, r.params_json);
  for (size_t i = 0; i < r.values.size(); ++i) ins.bind(static_cast<int>(5 + i), r.values[i]);
  ins.run();
  const std::int64_t id = sqlite3_last_insert_rowid(db_);
  Stmt point(db_, "INSERT INTO design_points (campaign, design_index, run) VALUES (?1, ?2, ?3)");
  point.bind(1, campaign).bind(2, index).bind(3, id).run();
  Stmt size(db_, "UPDATE campaigns SET design_size = ?2 WHERE id = ?1");
  size.bind(1, campaign).bind(2, index + 1).run();
  t.commit();
  return id;
}

std::optional<StoredRun> CampaignStore::find_run(std::int64_t campaign, const std::string& param_hash) {
  Stmt s(db_,
         "SELECT id, design_index, status, coalesce(message, ''), attempts, coalesce(wall_s, 0), "
         "coalesce(run_dir, ''), coalesce(h5_path, '') FROM runs WHERE campaign = ?1 AND param_hash = ?2");
  s.bind(1, campaign).bind(2, param_hash);
  if (!s.step()) return std::nullopt;
  StoredRun r;
  r.id = s.i64(0);
  r.design_index = s.i64(1);
  r.status = run_status_from(s.text(2)).value_or(RunStatus::kFailed);
  r.message = s.text(3);
  r.attempts = s.i64(4);
  r.wall_s = s.f64(5);
  r.run_dir = s.text(6);
  r.h5_path = s.text(7);
  return r;
}

RunTicket CampaignStore::claim_run(std::int64_t run_id, const std::string& host, const std::string& worker) {
  Transaction t(db_);
  Stmt s(db_,
         "UPDATE runs SET status = 'running', attempts = attempts + 1, "
         "started = strftime('%Y-%m-%dT%H:%M:%fZ', 'now'), finished = NULL, message = NULL, host = ?2, worker = ?3 "
         "WHERE id = ?1 AND status = 'pending' RETURNING design_index, attempts");
  s.bind(1, run_id).bind(2, host).bind(3, worker);
  if (!s.step()) throw StoreError("run " + std::to_string(run_id) + " is not pending");
  RunTicket ticket{run_id, s.i64(0), s.i64(1)};
  s.run();
  t.commit();
  return ticket;
}

void CampaignStore::record_evaluation(std::int64_t campaign, const Evaluation& e) {
  Transaction t(db_);
  Stmt s(db_,
         "INSERT OR REPLACE INTO evaluations (campaign, phase, start, seq, run, params, value, terms) "
         "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)");
  s.bind(1, campaign).bind(2, e.phase).bind(3, e.start).bind(4, e.seq);
  e.run > 0 ? s.bind(5, e.run) : s.bind_null(5);
  s.bind(6, e.params_json);
  std::isfinite(e.value) ? s.bind(7, e.value) : s.bind_null(7);
  s.bind(8, e.terms_json).run();
  t.commit();
}

void CampaignStore::delete_evaluations(std::int64_t campaign, const std::string& phase,
                                       std::int64_t from_start) {
  Transaction t(db_);
  Stmt s(db_, "DELETE FROM evaluations WHERE campaign = ?1 AND phase = ?2 AND start >= ?3");
  s.bind(1, campaign).bind(2, phase).bind(3, from_start).run();
  t.commit();
}

std::vector<Evaluation> CampaignStore::evaluations(std::int64_t campaign) {
  Stmt s(db_,
         "SELECT phase, start, seq, coalesce(run, 0), params, value, coalesce(terms, '{}') FROM evaluations "
         "WHERE campaign = ?1 ORDER BY phase, start, seq");
  s.bind(1, campaign);
  std::vector<Evaluation> out;
  while (s.step()) {
    Evaluation e;
    e.phase = s.text(0);
    e.start = s.i64(1);
    e.seq = s.i64(2);
    e.run = s.i64(3);
    e.params_json = s.text(4);
    e.value = s.null(5) ? std::nan("") : s.f64(5);
    e.terms_json = s.text(6);
    out.push_back(std::move(e));
  }
  return out;
}

void CampaignStore::save_surrogate(const SurrogateRecord& r) {
  Transaction t(db_);
  Stmt s(db_,
         "INSERT OR REPLACE INTO surrogates (campaign, metric, kind, settings, runs, runs_hash, quality, model, "
         "created) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, strftime('%Y-%m-%dT%H:%M:%fZ', 'now'))");
  s.bind(1, r.campaign).bind(2, r.metric).bind(3, r.kind).bind(4, r.settings_json).bind(5, r.runs_json);
  s.bind(6, r.runs_hash).bind(7, r.quality_json).bind(8, r.model).run();
  t.commit();
}

std::vector<SurrogateRecord> CampaignStore::surrogates(std::int64_t campaign, bool with_model) {
  std::vector<SurrogateRecord> out;
  {
    Stmt has(db_, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'surrogates'");
    has.step();
    if (has.i64(0) == 0) return out;  // a file from before surrogates, opened read-only
  }
  Stmt s(db_, std::string("SELECT id, campaign, metric, kind, settings, runs, runs_hash, quality, ") +
                  (with_model ? "model" : "''") +
                  ", created FROM surrogates WHERE campaign = ?1 ORDER BY metric, kind");
  s.bind(1, campaign);
  while (s.step()) {
    SurrogateRecord r;
    r.id = s.i64(0);
    r.campaign = s.i64(1);
    r.metric = s.text(2);
    r.kind = s.text(3);
    r.settings_json = s.text(4);
    r.runs_json = s.text(5);
    r.runs_hash = s.text(6);
    r.quality_json = s.text(7);
    r.model = s.text(8);
    r.created = s.text(9);
    out.push_back(std::move(r));
  }
  return out;
}

std::optional<SurrogateRecord> CampaignStore::find_surrogate(std::int64_t campaign, const std::string& metric,
                                                             const std::string& kind) {
  for (auto& r : surrogates(campaign))
    if (r.metric == metric && r.kind == kind) return r;
  return std::nullopt;
}

StatusSummary CampaignStore::summary(std::int64_t campaign) {
  StatusSummary s;
  {
    Stmt c(db_, "SELECT status, count(*) FROM runs WHERE campaign = ?1 GROUP BY status");
    c.bind(1, campaign);
    while (c.step())
      if (auto st = run_status_from(c.text(0))) s.counts[*st] = c.i64(1);
  }
  {
    Stmt f(db_,
           "SELECT design_index, status, coalesce(message, '') FROM runs WHERE campaign = ?1 "
           "AND status IN ('unstable', 'failed', 'timeout') ORDER BY design_index");
    f.bind(1, campaign);
    while (f.step()) s.failures.push_back({f.i64(0), *run_status_from(f.text(1)), f.text(2)});
  }
  {
    Stmt w(db_, "SELECT avg(wall_s) FROM runs WHERE campaign = ?1 AND finished IS NOT NULL");
    w.bind(1, campaign);
    if (w.step() && !w.null(0)) s.mean_wall_s = w.f64(0);
  }
  {
    // Rate over the latest 50 finishes: recent enough to follow the current job, long enough to be steady.
    Stmt r(db_,
           "SELECT count(*), (max(julianday(finished)) - min(julianday(finished))) * 86400.0 FROM "
           "(SELECT finished FROM runs WHERE campaign = ?1 AND finished IS NOT NULL ORDER BY finished DESC LIMIT 50)");
    r.bind(1, campaign);
    if (r.step() && r.i64(0) >= 2 && r.f64(1) > 0) s.throughput_per_h = (r.i64(0) - 1) / r.f64(1) * 3600.0;
  }
  return s;
}

void CampaignStore::export_csv(std::optional<std::int64_t> campaign, std::ostream& out) {
  std::vector<CampaignRecord> list;
  for (auto& c : campaigns())
    if (!campaign || c.id == *campaign) list.push_back(c);
  // Union of the columns of the selected campaigns' views, so several campaigns share one header.
  std::vector<std::string> header = {"campaign"};
  std::vector<std::vector<std::map<std::string, std::string>>> rows;
  for (const auto& c : list) {
    Stmt s(db_, results_select(c.id, nullptr));
    for (int i = 0; i < s.columns(); ++i)
      if (std::find(header.begin(), header.end(), s.column_name(i)) == header.end()) header.push_back(s.column_name(i));
    std::vector<std::map<std::string, std::string>> these;
    while (s.step()) {
      std::map<std::string, std::string> row{{"campaign", c.name}};
      for (int i = 0; i < s.columns(); ++i) {
        if (s.null(i)) continue;
        row[s.column_name(i)] = s.type(i) == SQLITE_FLOAT ? format_number(s.f64(i)) : s.text(i);
      }
      these.push_back(std::move(row));
    }
    rows.push_back(std::move(these));
  }
  for (size_t i = 0; i < header.size(); ++i) out << (i ? "," : "") << csv(header[i]);
  out << "\n";
  for (const auto& these : rows)
    for (const auto& row : these) {
      for (size_t i = 0; i < header.size(); ++i) {
        auto it = row.find(header[i]);
        out << (i ? "," : "") << (it == row.end() ? "" : csv(it->second));
      }
      out << "\n";
    }
}

std::string CampaignStore::integrity_check() {
  Stmt s(db_, "PRAGMA integrity_check");
  std::string out;
  while (s.step()) out += (out.empty() ? "" : "; ") + s.text(0);
  return out;
}

}  // namespace flume::store
