// Read-only queries over the campaign store, for the report.
#include "report/campaign_data.h"

#include <sqlite3.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "common/errors.h"

namespace flume::report {
namespace {

using json = nlohmann::json;

std::string quote_id(const std::string& name) {
  std::string q = "\"";
  for (char c : name) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

struct Db {
  sqlite3* h = nullptr;
  ~Db() { sqlite3_close(h); }
};

struct Query {
  Query(sqlite3* db, const std::string& sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s_, nullptr) != SQLITE_OK)
      throw store::StoreError(std::string("SQL prepare failed: ") + sqlite3_errmsg(db));
  }
  ~Query() { sqlite3_finalize(s_); }
  Query& bind(int i, std::int64_t v) {
    sqlite3_bind_int64(s_, i, v);
    return *this;
  }
  bool step() {
    const int rc = sqlite3_step(s_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw store::StoreError(std::string("SQL step failed: ") + sqlite3_errmsg(db_));
  }
  std::int64_t i64(int c) const { return sqlite3_column_int64(s_, c); }
  double f64(int c) const { return sqlite3_column_double(s_, c); }
  bool null(int c) const { return sqlite3_column_type(s_, c) == SQLITE_NULL; }
  bool is_text(int c) const { return sqlite3_column_type(s_, c) == SQLITE_TEXT; }
  std::string text(int c) const {
    const unsigned char* t = sqlite3_column_text(s_, c);
    return t ? reinterpret_cast<const char*>(t) : "";
  }

 private:
  sqlite3* db_;
  sqlite3_stmt* s_ = nullptr;
};

std::optional<store::ParamValue> param_from_json(const json& v) {
  store::ParamValue p;
  if (v.is_number()) {
    p.number = v.get<double>();
  } else if (v.is_string()) {
    p.is_text = true;
    p.text = v.get<std::string>();
  } else {
    return std::nullopt;
  }
  return p;
}

// A dotted path ("obstacles.layout") in a JSON document, or null.
const json* find_path(const json& root, const std::string& path) {
  const json* j = &root;
  std::stringstream ss(path);
  std::string key;
  while (std::getline(ss, key, '.')) {
    if (!j->is_object() || !j->contains(key)) return nullptr;
    j = &(*j)[key];
  }
  return j;
}

}  // namespace

int CampaignData::parameter_index(const std::string& path) const {
  for (std::size_t i = 0; i < parameters.size(); ++i)
    if (parameters[i].path == path) return static_cast<int>(i);
  return -1;
}

CampaignData load_campaign(const std::string& db_file, const std::string& campaign_name) {
  CampaignData d;
  d.db_file = db_file;
  {
    std::ifstream probe(db_file);
    if (!probe) throw InputError(db_file, "--db", "cannot open the campaign database (no such file?)");
  }
  {
    // The store's own checks: a file that is not a flume store, or of another schema version, is refused.
    store::CampaignStore st(db_file, /*read_only=*/true);
    const auto all = st.campaigns();
    std::string names;
    for (const auto& c : all) names += (names.empty() ? "" : ", ") + c.name;
    if (campaign_name.empty()) {
      if (all.size() != 1)
        throw InputError(
            db_file, "--campaign",
            "is required: the store holds " + std::to_string(all.size()) + " campaigns (" + names + ")");
      d.record = all.front();
    } else {
      const auto c = st.find_campaign(campaign_name);
      if (!c)
        throw InputError(db_file, "--campaign",
                         "no campaign named '" + campaign_name +
                             "' (the store has: " + (names.empty() ? "none" : names) + ")");
      d.record = *c;
    }
  }
  d.saltelli_base_size = static_cast<std::size_t>(std::max<std::int64_t>(0, d.record.saltelli_base_size));

  // The spec the campaign was run with (validated when it was run): target, overrides, design type.
  try {
    const json spec = json::parse(d.record.spec);
    if (spec.contains("model") && spec["model"].is_string()) d.model = spec["model"].get<std::string>();
    if (spec.contains("scene") && spec["scene"].is_string()) d.scene = spec["scene"].get<std::string>();
    if (spec.contains("design") && spec["design"].contains("type") && spec["design"]["type"].is_string())
      d.design_type = spec["design"]["type"].get<std::string>();
    if ((d.design_type == "monte_carlo" || d.design_type == "lhs" || d.design_type == "sobol") &&
        spec["design"].contains("samples") && spec["design"]["samples"].is_number_unsigned())
      d.design_samples = spec["design"]["samples"].get<std::size_t>();
    if (spec.contains("overrides") && spec["overrides"].is_object())
      for (auto it = spec["overrides"].begin(); it != spec["overrides"].end(); ++it)
        if (auto v = param_from_json(it.value())) {
          d.fixed[it.key()] = *v;
          d.fixed_source[it.key()] = "overrides";
        }
  } catch (const json::exception& e) {
    throw InputError(db_file, "campaigns." + d.record.name + ".spec",
                     std::string("is not valid JSON: ") + e.what());
  }
  if (!d.scene.empty()) {
    // Values the report draws with, from the scene file when it is still there (a missing file is not an
    // error: the geometry falls back to its defaults and says so).
    std::ifstream in(d.scene);
    if (in) {
      try {
        const json scene = json::parse(in);
        for (const std::string path : {"obstacles.layout", "basin.width_m"}) {
          if (d.fixed.count(path)) continue;
          if (const json* v = find_path(scene, path))
            if (auto p = param_from_json(*v)) {
              d.fixed[path] = *p;
              d.fixed_source[path] = "scene";
            }
        }
      } catch (const json::exception&) {
      }
    }
  }

  Db db;
  if (sqlite3_open_v2(db_file.c_str(), &db.h, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK)
    throw InputError(db_file, "--db",
                     std::string("cannot open the campaign database: ") + sqlite3_errmsg(db.h));
  sqlite3_busy_timeout(db.h, 30000);
  {
    Query p(db.h, "SELECT path, sql_type FROM parameters WHERE campaign = ?1 ORDER BY position");
    p.bind(1, d.record.id);
    while (p.step()) d.parameters.push_back({p.text(0), p.text(1) == "TEXT"});
  }
  std::string sql = "SELECT d.design_index, r.id, r.status, coalesce(r.message, '')";
  for (const auto& p : d.parameters) sql += ", r." + quote_id(p.path);
  sql += " FROM design_points d JOIN runs r ON r.id = d.run WHERE d.campaign = ?1 ORDER BY d.design_index";
  {
    Query q(db.h, sql);
    q.bind(1, d.record.id);
    while (q.step()) {
      RunRow row;
      row.design_index = q.i64(0);
      row.run_id = q.i64(1);
      row.status = store::run_status_from(q.text(2)).value_or(store::RunStatus::kFailed);
      row.message = q.text(3);
      for (std::size_t j = 0; j < d.parameters.size(); ++j) {
        store::ParamValue v;
        const int c = static_cast<int>(4 + j);
        if (q.is_text(c)) {
          v.is_text = true;
          v.text = q.text(c);
        } else {
          v.number = q.null(c) ? std::nan("") : q.f64(c);
        }
        row.params.push_back(v);
      }
      d.rows.push_back(std::move(row));
    }
  }
  std::map<std::int64_t, std::map<std::string, double>> by_run;
  std::set<std::string> names;
  {
    Query m(db.h,
            "SELECT m.run, m.name, m.value FROM metrics m JOIN runs r ON r.id = m.run WHERE r.campaign = ?1");
    m.bind(1, d.record.id);
    while (m.step()) {
      names.insert(m.text(1));
      if (!m.null(2)) by_run[m.i64(0)][m.text(1)] = m.f64(2);
    }
  }
  for (auto& row : d.rows) {
    auto it = by_run.find(row.run_id);
    if (it != by_run.end() && row.ok()) row.metrics = it->second;
  }
  d.metric_names.assign(names.begin(), names.end());
  return d;
}

}  // namespace flume::report
