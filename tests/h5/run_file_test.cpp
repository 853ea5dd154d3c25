#include "store/h5/run_file.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using flume::h5::Field;
using flume::h5::Reader;
using flume::h5::RunFile;

namespace {

// A fresh directory per test, so tests run in parallel under ctest without sharing files.
class RunFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("flume_h5_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string result() const { return (dir_ / "result.h5").string(); }
  std::set<std::string> files() const {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.insert(e.path().filename().string());
    return names;
  }
  fs::path dir_;
};

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST_F(RunFileTest, SeriesMatricesAndAttributesRoundTrip) {
  std::vector<double> t{0.0, 0.1, 0.2, 0.3};
  std::vector<double> eta{0.01, -0.02, 0.035, 1e-9};
  std::vector<double> vel{1, 2, 3, 4, 5, 6, 7, 8};  // 4 x 2
  {
    RunFile f(result());
    f.write_series("/gauges/g1", "time", t);
    f.write_series("/gauges/g1", "elevation", eta);
    f.write_series("/diagnostics", "mass", {});
    f.write_matrix("/probes/p1", "velocity", vel, 2);
    f.set_attribute("/", "scene", "flume <wave> & \"co\"");
    f.set_attribute("/", "status", "running");
    f.set_attribute("/", "status", "complete");  // replaced, not duplicated
    f.set_attribute("/", "message", "");
    f.set_attribute("/gauges/g1", "x_m", 12.5);
    f.set_attribute("/gauges/g1", "index", 7);
    f.finalize();
    EXPECT_TRUE(f.finalized());
  }
  Reader r(result());
  EXPECT_EQ(r.read_vector("/gauges/g1/time"), t);
  EXPECT_EQ(r.read_vector("/gauges/g1/elevation"), eta);
  EXPECT_EQ(r.shape("/gauges/g1/elevation"), (std::vector<std::size_t>{4}));
  EXPECT_EQ(r.read_vector("/probes/p1/velocity"), vel);
  EXPECT_EQ(r.shape("/probes/p1/velocity"), (std::vector<std::size_t>{4, 2}));
  EXPECT_TRUE(r.read_vector("/diagnostics/mass").empty());
  EXPECT_EQ(r.shape("/diagnostics/mass"), (std::vector<std::size_t>{0}));
  EXPECT_EQ(r.list("/"), (std::vector<std::string>{"diagnostics", "gauges", "probes"}));
  EXPECT_EQ(r.list("/gauges/g1"), (std::vector<std::string>{"elevation", "time"}));
  EXPECT_EQ(r.string_attribute("/", "scene"), "flume <wave> & \"co\"");
  EXPECT_EQ(r.string_attribute("/", "status"), "complete");
  EXPECT_EQ(r.string_attribute("/", "message"), "");
  EXPECT_FALSE(r.string_attribute("/", "flume_version").empty());
  EXPECT_DOUBLE_EQ(r.number_attribute("/gauges/g1", "x_m"), 12.5);
  EXPECT_DOUBLE_EQ(r.number_attribute("/gauges/g1", "index"), 7.0);
  EXPECT_DOUBLE_EQ(r.number_attribute("/", "snapshot_count"), 0.0);
  EXPECT_TRUE(r.exists("/probes/p1/velocity"));
  EXPECT_FALSE(r.exists("/probes/p2/velocity"));
  EXPECT_THROW(r.read_vector("/gauges/g1/missing"), std::runtime_error);
  EXPECT_THROW(r.number_attribute("/", "scene"), std::runtime_error);
  EXPECT_EQ(flume::h5::read_vector(result(), "/gauges/g1/time"), t);
  // No snapshots: no sidecar.
  EXPECT_FALSE(fs::exists(dir_ / "result.xmf"));
}

TEST_F(RunFileTest, RejectsBadShapesNamesAndDuplicates) {
  RunFile f(result());
  EXPECT_THROW(f.write_matrix("/loads/l1", "force", {1, 2, 3}, 2), std::invalid_argument);
  EXPECT_THROW(f.write_matrix("/loads/l1", "force", {1, 2}, 0), std::invalid_argument);
  EXPECT_THROW(f.write_series("/gauges", "a/b", {1.0}), std::invalid_argument);
  EXPECT_THROW(f.write_series("/gauges", "", {1.0}), std::invalid_argument);
  f.write_series("/gauges/g1", "time", {1.0});
  EXPECT_THROW(f.write_series("/gauges/g1", "time", {2.0}), std::invalid_argument);
  float xyz[3] = {0, 0, 0};
  EXPECT_THROW(f.add_snapshot(0.0, 1, xyz, {{"xyz", xyz}}), std::invalid_argument);
  EXPECT_THROW(f.add_snapshot(0.0, 1, xyz, {{"p", xyz}}, {{"p", xyz}}), std::invalid_argument);
  EXPECT_THROW(f.add_snapshot(0.0, 1, nullptr), std::invalid_argument);
  f.finalize();
  EXPECT_THROW(f.write_series("/gauges/g2", "time", {1.0}), std::logic_error);
  EXPECT_THROW(f.finalize(), std::logic_error);
}

TEST_F(RunFileTest, PartFileUntilFinalizeThenRenamed) {
  RunFile f(result());
  f.write_series("/diagnostics", "time", {0.0, 1.0});
  f.flush();
  EXPECT_EQ(files(), (std::set<std::string>{"result.h5.part"}));
  EXPECT_EQ(f.part_path(), result() + ".part");
  f.finalize();
  EXPECT_EQ(files(), (std::set<std::string>{"result.h5"}));
}

TEST_F(RunFileTest, DestructorWithoutFinalizeLeavesOnlyThePartFile) {
  {
    RunFile f(result());
    f.write_series("/diagnostics", "time", {0.0, 1.0});
  }
  EXPECT_EQ(files(), (std::set<std::string>{"result.h5.part"}));
  // What was written is still readable from the .part (closed cleanly by the destructor).
  EXPECT_EQ(flume::h5::read_vector(result() + ".part", "/diagnostics/time"), (std::vector<double>{0.0, 1.0}));
}

TEST_F(RunFileTest, StaleResultFromAnEarlierRunIsRemovedAtStart) {
  {
    RunFile f(result());
    f.finalize();
  }
  ASSERT_TRUE(fs::exists(result()));
  RunFile again(result());
  EXPECT_FALSE(fs::exists(result()));
}

TEST_F(RunFileTest, KilledProcessLeavesNoFinalFile) {
  // A child writes and dies without unwinding (as under SIGKILL); only the .part may remain.
  pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    RunFile f(result());
    f.write_series("/diagnostics", "time", {0.0, 1.0});
    std::_Exit(9);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_FALSE(fs::exists(result()));
  EXPECT_TRUE(fs::exists(result() + ".part"));
}

TEST_F(RunFileTest, CannotCreateNamesTheFile) {
  std::string bad = (dir_ / "no_such_dir" / "result.h5").string();
  try {
    RunFile f(bad);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad + ".part"), std::string::npos) << e.what();
  }
}

TEST_F(RunFileTest, SnapshotsRoundTripWithXdmfSidecar) {
  const std::size_t n = 1000;
  std::vector<float> xyz(3 * n), p(n), v(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    xyz[3 * i] = 0.01f * i;
    xyz[3 * i + 1] = 0.5f;
    xyz[3 * i + 2] = -0.25f * (i % 7);
    p[i] = 1000.0f + i;
    v[3 * i] = 1.0f;
    v[3 * i + 1] = 0.0f;
    v[3 * i + 2] = -2.0f * i;
  }
  {
    RunFile f(result());
    EXPECT_EQ(f.add_snapshot(0.0, n, xyz.data(), {{"pressure", p.data()}}, {{"velocity", v.data()}}), 0u);
    EXPECT_EQ(f.add_snapshot(0.25, n / 2, xyz.data(), {{"pressure", p.data()}}), 1u);
    EXPECT_EQ(f.add_snapshot(0.5, 0, nullptr), 2u);  // every particle left the domain
    f.set_attribute("/", "status", "unstable");
    f.finalize();
  }
  Reader r(result());
  EXPECT_EQ(r.list("/snapshots"), (std::vector<std::string>{"00000", "00001", "00002"}));
  EXPECT_EQ(r.shape("/snapshots/00000/xyz"), (std::vector<std::size_t>{n, 3}));
  EXPECT_EQ(r.shape("/snapshots/00000/velocity"), (std::vector<std::size_t>{n, 3}));
  EXPECT_EQ(r.shape("/snapshots/00001/pressure"), (std::vector<std::size_t>{n / 2}));
  EXPECT_EQ(r.shape("/snapshots/00002/xyz"), (std::vector<std::size_t>{0, 3}));
  std::vector<double> got = r.read_vector("/snapshots/00000/xyz");
  ASSERT_EQ(got.size(), xyz.size());
  for (std::size_t i = 0; i < xyz.size(); ++i) ASSERT_EQ(static_cast<float>(got[i]), xyz[i]) << i;
  got = r.read_vector("/snapshots/00000/velocity");
  for (std::size_t i = 0; i < v.size(); ++i) ASSERT_EQ(static_cast<float>(got[i]), v[i]) << i;
  got = r.read_vector("/snapshots/00001/pressure");
  for (std::size_t i = 0; i < n / 2; ++i) ASSERT_EQ(static_cast<float>(got[i]), p[i]) << i;
  EXPECT_DOUBLE_EQ(r.number_attribute("/snapshots/00001", "time"), 0.25);
  EXPECT_DOUBLE_EQ(r.number_attribute("/", "snapshot_count"), 3.0);
  EXPECT_EQ(r.string_attribute("/", "status"), "unstable");

  // The sidecar: a temporal collection whose every HDF reference names a dataset with the stated size.
  std::string xmf = slurp((dir_ / "result.xmf").string());
  ASSERT_FALSE(xmf.empty());
  EXPECT_NE(xmf.find("CollectionType=\"Temporal\""), std::string::npos);
  EXPECT_NE(xmf.find("TopologyType=\"Polyvertex\""), std::string::npos);
  EXPECT_NE(xmf.find("<Time Value=\"0.25\"/>"), std::string::npos);
  EXPECT_NE(xmf.find("<Attribute Name=\"velocity\" AttributeType=\"Vector\""), std::string::npos);
  std::regex item(R"re(<DataItem Dimensions="([0-9 ]+)"[^>]*Format="HDF">([^:<]+):([^<]+)</DataItem>)re");
  int items = 0;
  for (auto it = std::sregex_iterator(xmf.begin(), xmf.end(), item); it != std::sregex_iterator(); ++it) {
    ++items;
    EXPECT_EQ((*it)[2].str(), "result.h5");
    std::string ds = (*it)[3].str();
    ASSERT_TRUE(r.exists(ds)) << ds;
    std::string dims;
    for (std::size_t d : r.shape(ds)) dims += (dims.empty() ? "" : " ") + std::to_string(d);
    EXPECT_EQ((*it)[1].str(), dims) << ds;
  }
  EXPECT_EQ(items, 3 + 2 + 1);  // xyz + pressure + velocity, xyz + pressure, xyz
  // Element balance: a cheap well-formedness check for the fixed structure written.
  auto count = [&](const std::string& s) {
    std::size_t c = 0;
    for (std::size_t pos = xmf.find(s); pos != std::string::npos; pos = xmf.find(s, pos + 1)) ++c;
    return c;
  };
  EXPECT_EQ(count("<Grid "), count("</Grid>"));
  EXPECT_EQ(count("<Attribute "), count("</Attribute>"));
  EXPECT_EQ(count("<DataItem "), count("</DataItem>"));
  EXPECT_EQ(files(), (std::set<std::string>{"result.h5", "result.xmf"}));
}

// h5ls (hdf5-tools) is optional: when present it must read the file and see the compression.
TEST_F(RunFileTest, H5lsReadsTheFileWhenInstalled) {
  if (std::system("command -v h5ls >/dev/null 2>&1") != 0) GTEST_SKIP() << "h5ls not found (scripts/setup installs hdf5-tools; the HDF5 library checks above do not need it)";
  std::vector<float> xyz(3 * 5000, 1.0f);
  {
    RunFile f(result());
    f.add_snapshot(0.0, 5000, xyz.data());
    f.finalize();
  }
  std::string out = (dir_ / "h5ls.txt").string();
  ASSERT_EQ(std::system(("h5ls -r -v " + result() + " > " + out + " 2>&1").c_str()), 0);
  std::string listing = slurp(out);
  EXPECT_NE(listing.find("/snapshots/00000/xyz"), std::string::npos) << listing;
  EXPECT_NE(listing.find("deflate"), std::string::npos) << listing;
}

}  // namespace

// Issue 29: a growing series is appended at each flush (only the new rows are written), and after flush() the
// .part file's bytes are an HDF5 file with every row so far, as a SIGKILL then would leave them (read from a
// copy: HDF5 will not open a second handle on a file this process has open for writing).
TEST_F(RunFileTest, AppendedSeriesGrowAtEachFlushAndThePartFileReadsBetween) {
  RunFile f(result());
  std::vector<double> t, v;  // v: 3 columns per row
  for (int flush = 0; flush < 3; ++flush) {
    for (int k = 0; k < 5 + flush; ++k) {
      t.push_back(0.1 * static_cast<double>(t.size()));
      for (int c = 0; c < 3; ++c) v.push_back(10.0 * static_cast<double>(t.size()) + c);
    }
    f.append_series("/gauges/g", "time", t);
    f.append_matrix("/probes/p", "velocity", v, 3);
    f.flush();
    const fs::path copy = dir_ / ("flushed-" + std::to_string(flush) + ".h5");
    fs::copy_file(f.part_path(), copy);
    Reader r(copy.string());
    EXPECT_EQ(r.read_vector("/gauges/g/time"), t);
    EXPECT_EQ(r.read_vector("/probes/p/velocity"), v);
    EXPECT_EQ(r.shape("/probes/p/velocity"), (std::vector<std::size_t>{t.size(), 3}));
  }
  f.append_series("/gauges/g", "time", t);  // nothing new: nothing written
  EXPECT_THROW(f.append_series("/gauges/g", "time", {0.0}), std::logic_error);     // shrank
  EXPECT_THROW(f.append_matrix("/probes/p", "velocity", v, 2), std::logic_error);  // other columns
  f.finalize();
  EXPECT_EQ(flume::h5::read_vector(result(), "/gauges/g/time"), t);
}
