// `flume run`, `flume bench`, `flume check`: argument parsing and exit codes over run_scene().
#include "solver/commands.h"

#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/errors.h"
#include "solver/run.h"
#include "solver/run_output.h"
#include "solver/scene.h"
#include "solver/simulation.h"

namespace flume {
namespace {

struct Args {
  std::string scene;
  std::string out;
  std::vector<Override> sets;
  SimulationOptions options;
  long steps = 0;
  bool quiet = false;
  CheckpointOptions checkpoints;
  double flush_every_s = kDefaultFlushEvery_s;
};

int parse_int(const char* flag, const char* text, long lo, long hi) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (*end || v < lo || v > hi)
    throw InputError(flag, "", "expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                                   "] (got '" + text + "')");
  return static_cast<int>(v);
}

// Wall-clock seconds in [lo, 1e7] (`lo_text` is lo as the message prints it).
double parse_seconds(const char* flag, const char* text, double lo, const char* lo_text) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (*end || !(v >= lo && v <= 1e7))
    throw InputError(flag, "", std::string("expects wall-clock seconds in [") + lo_text + ", 1e7] (got '" + text + "')");
  return v;
}

// Parses the options shared by the solver's commands. `need_out`/`need_steps` say which are required.
Args parse_args(int argc, char** argv, bool need_out, bool need_steps) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&](const char* flag) -> const char* {
      if (i + 1 >= argc) throw InputError(flag, "", "needs a value");
      return argv[++i];
    };
    if (s == "--out") {
      a.out = value("--out");
    } else if (s == "--set") {
      a.sets.push_back(parse_override(value("--set")));
    } else if (s.rfind("--set=", 0) == 0) {
      a.sets.push_back(parse_override(s.substr(6)));
    } else if (s == "--threads") {
      a.options.threads = parse_int("--threads", value("--threads"), 1, 1024);
    } else if (s == "--steps") {
      a.steps = parse_int("--steps", value("--steps"), 1, 1000000000);
    } else if (s == "--backend") {
      const std::string b = value("--backend");
      if (b == "cpu") {
        a.options.backend = Backend::kCpu;
      } else if (b == "cuda") {
        a.options.backend = Backend::kCuda;
      } else {
        throw InputError("--backend", "", "must be cpu or cuda (got '" + b + "')");
      }
    } else if (s == "--checkpoint-every") {
      a.checkpoints.every_s = parse_seconds("--checkpoint-every", value("--checkpoint-every"), 1, "1");
    } else if (s == "--flush-every") {
      a.flush_every_s = parse_seconds("--flush-every", value("--flush-every"), 0.1, "0.1");
    } else if (s == "--resume") {
      a.checkpoints.resume = true;
    } else if (s == "--quiet" || s == "-q") {
      a.quiet = true;
    } else if (!s.empty() && s[0] == '-') {
      throw InputError(argv[0], s, "unknown option");
    } else if (a.scene.empty()) {
      a.scene = s;
    } else {
      throw InputError(argv[0], s, "unexpected argument (one scene file only)");
    }
  }
  if (a.scene.empty()) throw InputError(argv[0], "", "needs a scene file (SCENE.json)");
  if (need_out && a.out.empty()) throw InputError(argv[0], "--out", "is required (the run's output directory)");
  if (need_steps && a.steps <= 0) throw InputError(argv[0], "--steps", "is required (a positive step count)");
  return a;
}

template <typename F>
int guarded(const char* cmd, F&& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::fprintf(stderr, "flume %s: error: %s\n", cmd, e.what());
    return kExitInvalidInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flume %s: internal error: %s\n", cmd, e.what());
    return kExitInternal;
  }
}

}  // namespace

int run_main(int argc, char** argv) {
  return guarded("run", [&]() -> int {
    const Args a = parse_args(argc, argv, true, false);
    const Scene scene = load_scene(a.scene, a.sets);
    install_stop_handlers();
    const RunOutcome r = run_scene(scene, a.options, a.out, !a.quiet, a.checkpoints, a.flush_every_s);
    std::fprintf(stderr, "flume run: %s: %s (%ld steps, %zu particles, %.1f s, %.3g particle-steps/s)\n",
                 status_name(r.status).c_str(), r.message.c_str(), r.cost.steps, r.cost.particles, r.cost.wall_s,
                 r.cost.particle_steps_per_s);
    if (r.status == RunStatus::kKilled) return 128 + stop_signal();
    return r.status == RunStatus::kOk ? kExitOk : kExitUnstable;
  });
}

int bench_main(int argc, char** argv) {
  return guarded("bench", [&] {
    Args a = parse_args(argc, argv, false, true);
    const Scene scene = load_scene(a.scene, a.sets);
    auto sim = make_simulation(scene, a.options);
    // One warm-up step builds the block lists and touches the memory; the measured steps follow.
    sim->step();
    const long steps0 = sim->steps();
    const auto t0 = std::chrono::steady_clock::now();
    RunStatus st = RunStatus::kRunning;
    for (long i = 0; i < a.steps && st == RunStatus::kRunning; ++i) st = sim->step();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const long steps = sim->steps() - steps0;
    nlohmann::json j = {{"scene", scene.file},
                        {"dimension", scene.dimension},
                        {"precision", to_string(scene.solver.precision)},
                        {"backend", a.options.backend == Backend::kCuda ? "cuda" : "cpu"},
                        {"threads", a.options.threads > 0 ? a.options.threads : omp_get_max_threads()},
                        {"dx", scene.solver.dx},
                        {"status", st == RunStatus::kUnstable ? "unstable" : "ok"},
                        {"wall_s", wall},
                        {"steps", steps},
                        {"particles", sim->particle_count()},
                        {"particle_steps_per_s", wall > 0 ? double(steps) * double(sim->particle_count()) / wall : 0},
                        {"peak_rss_mb", peak_rss_mb()},
                        {"grid_mb", sim->grid_bytes() / 1048576.0},
                        {"active_blocks", sim->active_blocks()}};
    std::printf("%s\n", j.dump(2).c_str());
    return st == RunStatus::kUnstable ? kExitUnstable : kExitOk;
  });
}

int check_main(int argc, char** argv) {
  return guarded("check", [&] {
    const Args a = parse_args(argc, argv, false, false);
    const Scene s = load_scene(a.scene, a.sets);
    std::printf("%s: scene '%s', %dD, dx = %g m, ppc = %d, %s, end_time = %g s, %zu water boxes, %zu boundaries\n",
                s.file.c_str(), s.name.c_str(), s.dimension, s.solver.dx, s.solver.ppc,
                to_string(s.solver.precision), s.solver.end_time, s.water.size(), s.boundaries.size());
    return kExitOk;
  });
}

}  // namespace flume
