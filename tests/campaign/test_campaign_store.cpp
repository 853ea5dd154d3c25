// The SQLite store on its own: schema version, idempotent planning, claim/record, resume.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <sstream>

#include "common/errors.h"
#include "store/db/campaign_store.h"

using namespace flume::store;

namespace {

std::string fresh_db(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("flume_store_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / (name + ".db");
  std::filesystem::remove(file);
  return file.string();
}

std::vector<PlannedRun> plan(int n) {
  std::vector<PlannedRun> runs;
  for (int i = 0; i < n; ++i) {
    PlannedRun r;
    r.design_index = i;
    r.param_hash = "h" + std::to_string(i % 3 == 2 ? i - 1 : i);  // every third point repeats its predecessor
    r.params_json = "{}";
    ParamValue v;
    v.number = i;
    r.values = {v};
    runs.push_back(r);
  }
  return runs;
}

std::int64_t make_campaign(CampaignStore& db, int n) {
  CampaignRecord c;
  c.name = "c1";
  c.spec = "{}";
  c.spec_hash = "abc";
  c.code_version = "test";
  c.design_size = n;
  return db.create_campaign(c, {{"x", false}}, plan(n));
}

}  // namespace

TEST(CampaignStore, RepeatedParameterSetsAreOneRun) {
  CampaignStore db(fresh_db("dups"));
  const auto id = make_campaign(db, 9);
  const StatusSummary s = db.summary(id);
  EXPECT_EQ(s.counts.at(RunStatus::kPending), 6);  // 9 design points, 3 of them repeats
  std::ostringstream csv;
  db.export_csv(id, csv);
  // Header plus one line per design point (repeats included, pointing at the same run).
  const std::string text = csv.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 10);
}

TEST(CampaignStore, ClaimRecordAndResume) {
  const std::string file = fresh_db("resume");
  std::int64_t id = 0;
  {
    CampaignStore db(file);
    id = make_campaign(db, 3);
    auto a = db.claim_next(id, "host", "w1");
    auto b = db.claim_next(id, "host", "w2");
    ASSERT_TRUE(a && b);
    EXPECT_NE(a->run_id, b->run_id);
    RunOutcome o;
    o.status = RunStatus::kOk;
    o.metrics = {{"y", 1.5}};
    db.record_outcome(a->run_id, o);
    // b stays `running`: the job dies here.
  }
  CampaignStore db(file);
  EXPECT_EQ(db.prepare_resume(id, plan(3)), 1);  // b back to pending, a untouched
  const StatusSummary s = db.summary(id);
  EXPECT_EQ(s.counts.at(RunStatus::kOk), 1);
  EXPECT_EQ(s.counts.at(RunStatus::kPending), 1);
  EXPECT_EQ(s.counts.count(RunStatus::kRunning), 0u);
  auto next = db.claim_next(id, "host", "w1");
  ASSERT_TRUE(next);
  EXPECT_EQ(next->attempt, 2);  // redone, and counted as such
  EXPECT_EQ(db.integrity_check(), "ok");
}

TEST(CampaignStore, OtherSchemaVersionIsRefused) {
  const std::string file = fresh_db("version");
  { CampaignStore db(file); }
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, "UPDATE meta SET value = '99' WHERE key = 'schema_version'", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  try {
    CampaignStore db(file);
    FAIL() << "a store of schema version 99 was opened";
  } catch (const flume::InputError& e) {
    EXPECT_EQ(e.field(), "meta.schema_version");
    EXPECT_NE(std::string(e.what()).find("99"), std::string::npos);
  }
}

TEST(CampaignStore, ParameterNamedLikeABuiltInColumnIsRefused) {
  CampaignStore db(fresh_db("builtin"));
  CampaignRecord c;
  c.name = "c";
  c.spec = "{}";
  c.spec_hash = "h";
  c.code_version = "t";
  EXPECT_THROW(db.create_campaign(c, {{"status", false}}, {}), flume::InputError);
  EXPECT_TRUE(db.campaigns().empty());  // the failed transaction left nothing behind
}

// Issue 29: the writer lock belongs to the database file: a second writer through the same path, a symlink or
// a hard link is refused naming the path it was given (this process's pid as the holder), a reader is not,
// and the lock goes with the first store.
TEST(CampaignStore, SecondWriterThroughAnyPathIsRefusedAndReadersAreNot) {
  const std::string file = fresh_db("locked");
  const std::string sym = file + ".symlink", hard = file + ".hardlink";
  std::filesystem::remove(sym);
  std::filesystem::remove(hard);
  {
    CampaignStore writer(file);
    make_campaign(writer, 3);
    std::filesystem::create_symlink(file, sym);
    std::filesystem::create_hard_link(file, hard);
    for (const std::string& path : {file, sym, hard}) {
      try {
        CampaignStore second(path);
        ADD_FAILURE() << path << ": a second writer was let in";
      } catch (const flume::InputError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(e.problem().find("another flume job (pid " + std::to_string(getpid()) + ")"), std::string::npos)
            << e.what();
      }
      // A reader through a hard link would look for "<link>-wal", not the writer's log: not tried here.
      if (path == hard) continue;
      CampaignStore reader(path, /*read_only=*/true);
      EXPECT_EQ(reader.campaigns().size(), 1u);
    }
  }
  CampaignStore again(hard);  // the first writer closed: the lock is free
  EXPECT_EQ(again.campaigns().size(), 1u);
}
