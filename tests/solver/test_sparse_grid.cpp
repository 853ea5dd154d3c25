// Sparse grid (issue 2, item 5): the same water in a domain 20 times larger PER AXIS (400x the area in 2D,
// 8000x the volume in 3D) must take less than 1.5x the grid memory. Only blocks near particles exist, so
// the grid should not notice the domain at all. The time per step is measured by `flume bench` (bench/,
// docs/benchmarks.md), not here: tests make no timing assertions.
//
// Both domains share their lower corner, so the block lattice sits identically on the water; the far walls
// are out of the water's reach during the run, so the two runs must be the same computation: the particle
// state is compared bitwise as well.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>
#include <string>

#include "solver/block_sort.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

// A dam break: a water box in the corner of the domain [0, hi] (floor and left wall are the domain's).
std::string dam_break(int dim, double scale) {
  const double dx = dim == 2 ? 0.01 : 0.02;
  const std::string hi = dim == 2
                             ? "[" + std::to_string(0.8 * scale) + ", " + std::to_string(0.4 * scale) + "]"
                             : "[" + std::to_string(0.6 * scale) + ", " + std::to_string(0.4 * scale) + ", " +
                                   std::to_string(0.4 * scale) + "]";
  const std::string wlo = dim == 2 ? "[0.04, 0.04]" : "[0.04, 0.04, 0.04]";
  const std::string whi = dim == 2 ? "[0.24, 0.24]" : "[0.16, 0.16, 0.2]";
  return R"({"name": "sparse", "dimension": )" + std::to_string(dim) + R"(,
    "domain": {"lo": )" +
         (dim == 2 ? "[0.0, 0.0]" : "[0.0, 0.0, 0.0]") + R"(, "hi": )" + hi + R"(},
    "solver": {"dx": )" +
         std::to_string(dx) + R"(, "ppc": )" + (dim == 2 ? "4" : "8") +
         R"(, "cfl": 0.4, "precision": "float", "end_time": 0.06},
    "fluid": {"bulk_modulus": 2.0e6, "jbar_psi": 0.5},
    "water": [{"lo": )" +
         wlo + R"(, "hi": )" + whi + R"(}]
  })";
}

struct Outcome {
  size_t grid_bytes_max = 0, blocks_max = 0, steps = 0;
  std::vector<double> xyz, vel;
};

Outcome run(const std::string& text) {
  const Scene scene = parse_scene_text(text, "sparse.json");
  auto sim = make_simulation(scene, {});
  Outcome o;
  RunStatus s = RunStatus::kRunning;
  while (s == RunStatus::kRunning) {
    s = sim->step();
    o.grid_bytes_max = std::max(o.grid_bytes_max, sim->grid_bytes());
    o.blocks_max = std::max(o.blocks_max, sim->active_blocks());
  }
  EXPECT_EQ(s, RunStatus::kOk) << sim->message();
  o.steps = sim->steps();
  sim->particle_positions(o.xyz);
  sim->particle_velocities(o.vel);
  return o;
}

void check(int dim) {
  const Outcome small = run(dam_break(dim, 1));
  const Outcome large = run(dam_break(dim, 20));
  std::printf(
      "[ info ] %dD, domain 20x per axis: grid %.3f MB -> %.3f MB (ratio %.3f), blocks %zu -> %zu, %zu "
      "steps\n",
      dim, small.grid_bytes_max / 1048576.0, large.grid_bytes_max / 1048576.0,
      double(large.grid_bytes_max) / double(small.grid_bytes_max), small.blocks_max, large.blocks_max,
      small.steps);
  ASSERT_GT(small.grid_bytes_max, 0u);
  EXPECT_LT(double(large.grid_bytes_max), 1.5 * double(small.grid_bytes_max));
  EXPECT_EQ(large.blocks_max, small.blocks_max);
  // The water moved (a dam break, not a still box) and did the same thing in both domains.
  EXPECT_EQ(large.steps, small.steps);
  EXPECT_EQ(large.xyz, small.xyz);
  EXPECT_EQ(large.vel, small.vel);
  double vmax = 0;
  for (double v : small.vel) vmax = std::max(vmax, std::fabs(v));
  EXPECT_GT(vmax, 0.3);
}

TEST(SparseGrid, Domain20xPerAxis2D) { check(2); }
TEST(SparseGrid, Domain20xPerAxis3D) { check(3); }

// The whole process, not just the grid the solver reports: `flume bench` in the 3D domain 20x per axis (whose
// dense grid would hold 9.6e7 nodes, gigabytes) peaks at less than 1.5x the resident memory of the small one.
// The particles' block order (solver/block_sort.h) is std::stable_sort's, for any thread count: the runs of a
// nearly sorted array with particles appended at the end (as an inflow adds them), ties kept in index order.
TEST(BlockSort, SameOrderAsStableSort) {
  std::mt19937_64 rng(7);
  for (const size_t n : {size_t(0), size_t(1), size_t(17), size_t(100000)}) {
    std::vector<uint64_t> key(n);
    // Blocks of 37 in order, some particles moved to other blocks, some appended (new blocks too).
    for (size_t i = 0; i < n; ++i) key[i] = i / 37;
    for (size_t i = 0; i < n / 20; ++i) key[rng() % n] = rng() % (n / 37 + 5);
    for (size_t i = 0; i < n / 10; ++i) key.push_back(rng() % (n / 37 + 100));
    std::vector<uint32_t> want(key.size());
    std::iota(want.begin(), want.end(), 0u);
    std::stable_sort(want.begin(), want.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
    const int threads_before = omp_get_max_threads();
    for (const int threads : {1, 2, 3}) {
      omp_set_num_threads(threads);
      std::vector<uint32_t> got;
      BlockSortWork work;
      stable_order_by_key(key, got, work);
      EXPECT_EQ(got, want) << n << " keys, " << threads << " threads";
    }
    omp_set_num_threads(threads_before);
  }
}

TEST(SparseGrid, ProcessMemoryFollowsTheWater) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("flume_test_sparse_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  double rss[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    const std::string scene = (dir / ("scene" + std::to_string(k) + ".json")).string();
    std::ofstream(scene) << dam_break(3, k ? 20 : 1);
    const std::string out = (dir / "bench.json").string();
    ASSERT_EQ(test::run_command(std::string(FLUME_EXE) + " bench " + scene + " --steps 50 >" + out), 0);
    rss[k] = nlohmann::json::parse(test::read_text(out)).at("peak_rss_mb").get<double>();
  }
  fs::remove_all(dir);
  std::printf("[ info ] flume bench peak RSS: %.1f MB (domain 1x) -> %.1f MB (20x per axis)\n", rss[0],
              rss[1]);
  EXPECT_LT(rss[1], 1.5 * rss[0]);
}

}  // namespace
}  // namespace flume
