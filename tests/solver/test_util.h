// Helpers shared by the solver tests.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "solver/scene.h"
#include "solver/simulation.h"

namespace flume::test {

// A measured record: shared/validation/REL beside the project when present, else the copy under tests/data.
inline std::string validation_file(const std::string& rel) {
  const std::string shared = std::string(FLUME_VALIDATION_DIR) + "/" + rel;
  if (std::ifstream(shared).good()) return shared;
  return std::string(FLUME_SOURCE_DIR) + "/tests/data/validation/" + rel;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Numeric rows of a CSV with '#' comment lines and one header line.
inline std::vector<std::vector<double>> read_csv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<double>> rows;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::vector<double> r;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) r.push_back(std::stod(cell));
    rows.push_back(r);
  }
  return rows;
}

// Runs a shell command, returning its exit status.
inline int run_command(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// Extra scene overrides from the environment, FLUME_SET="path=value;path=value", to measure a test's case
// with other settings (e.g. docs/sph.md's runs with and without shifting); none when unset.
inline std::vector<Override> env_overrides() {
  std::vector<Override> out;
  const char* v = std::getenv("FLUME_SET");
  std::stringstream ss(v ? v : "");
  std::string item;
  while (std::getline(ss, item, ';')) {
    const size_t eq = item.find('=');
    if (eq != std::string::npos) out.push_back({item.substr(0, eq), item.substr(eq + 1)});
  }
  return out;
}

inline RunStatus run_until(Simulation& sim, double t_end) {
  RunStatus s = RunStatus::kRunning;
  while (s == RunStatus::kRunning && sim.time() < t_end - 1e-12) s = sim.step();
  return s;
}

// What a finished run leaves: the particles' positions, velocities and pressures, the instruments' record and
// the number of steps (for comparing two runs of one scene, e.g. on different thread counts or kernel copies).
struct FinalState {
  std::vector<double> xyz, vel, p;
  Record record;
  long steps = 0;
};
inline FinalState final_state(const Simulation& sim) {
  FinalState s;
  sim.particle_positions(s.xyz);
  sim.particle_velocities(s.vel);
  sim.particle_pressures(s.p);
  s.record = sim.record();
  s.steps = sim.steps();
  return s;
}

// max |a - b| / max |a| over two series (of equal length; the shorter one's length otherwise).
inline double rel_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0, s = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    d = std::max(d, std::fabs(a[i] - b[i]));
    s = std::max(s, std::fabs(a[i]));
  }
  return s > 0 ? d / s : d;
}

// The CUDA backend on the device; the tests that use it skip where there is none (SKIP_WITHOUT_DEVICE).
inline std::unique_ptr<Simulation> gpu(const Scene& s) {
  SimulationOptions o;
  o.backend = Backend::kCuda;
  return make_simulation(s, o);
}

}  // namespace flume::test

// Skipping is the only honest outcome without a GPU: these tests compare execution on the device (its atomics'
// order, nvcc's arithmetic) with the CPU. The same CUDA source runs on the host against the CPU in every build
// (the CudaEmulation tests); bench/run_gpu_bench.sh runs these where a GPU is lent.
#define SKIP_WITHOUT_DEVICE() \
  if (!::flume::cuda_available())                                                                         \
  GTEST_SKIP() << "no CUDA device (or flume built without CUDA): this test compares execution on a GPU with "  \
                  "the CPU; the same CUDA source is checked on the host by CudaEmulation.*"
