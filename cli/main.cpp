// `flume`: the thin command line over the solver, campaign, calibration and report modules.
// Each subcommand lives in its module; this file only dispatches.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "calibration/commands.h"
#include "campaigns/commands.h"
#include "flume_version.h"
#include "report/gauges.h"
#include "report/paths.h"
#include "report/report.h"
#include "solver/commands.h"
#include "surrogate/commands.h"
#ifdef FLUME_HAVE_STUDY
#include "study/tradeoff.h"
#endif

namespace {

struct Command {
  const char* name;
  int (*main)(int argc, char** argv);  // argv[0] is the subcommand name
  const char* help;
};

const std::vector<Command>& commands() {
  static const std::vector<Command> list = {
      {"run", flume::run_main, "run SCENE.json --out DIR [--set path=value ...] [--threads N] [--backend cpu|cuda] [--checkpoint-every S] [--resume]"},
      {"bench", flume::bench_main, "bench SCENE.json --steps N [--set path=value ...] [--threads N]"},
      {"check", flume::check_main, "check SCENE.json [--set path=value ...]   validate a scene, print a summary"},
      {"campaign", flume::campaign_main, "campaign run SPEC.json --db FILE [--workers N] | status --db FILE | export --db FILE --csv OUT"},
      {"report", flume::report_main, "report --db FILE --campaign NAME --out DIR [--thresholds metric=v1,v2 ...]   HTML/JSON/CSV report"},
      {"debris-paths", flume::report::debris_paths_main, "debris-paths RUN_DIR [RUN_DIR ...] --out FILE.svg   top-down debris paths with the Naito and Nistor guidelines"},
      {"gauges", flume::report::gauges_main, "gauges RUN_DIR[=LABEL] [RUN_DIR[=LABEL] ...] --out FILE.svg [--gauges WG1,WG2,...] [--t-max S] [--title TEXT]   gauge records of runs, peaks and arrivals"},
      {"model", flume::model_main, "model ishigami|test --out DIR [--set name=value ...]   analytic stand-ins for `run`"},
#ifdef FLUME_HAVE_STUDY
      {"study", flume::study::study_main, "study tradeoff SPEC.json --db FILE [--out DIR] [--workers N]   error against cost over fidelity settings, Pareto front"},
#endif
      {"surrogate", flume::surrogate_main, "surrogate fit|predict|sobol|show --db FILE --campaign NAME --metric M ...   polynomial chaos and kriging surrogates of a campaign's runs"},
      {"calibrate", flume::calibration::calibrate_main, "calibrate SPEC.json --db FILE --out DIR [--workers N] | target RESULT.h5 --out CSV | history --db FILE"},
  };
  return list;
}

void usage(FILE* out) {
  std::fprintf(out, "flume %s (%s): tsunami-debris flume simulation and uncertainty campaigns\n\nusage:\n",
               FLUME_VERSION, FLUME_GIT_VERSION);
  for (const auto& c : commands()) std::fprintf(out, "  flume %s\n", c.help);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::printf("flume %s (%s)\n", FLUME_VERSION, FLUME_GIT_VERSION);
    return 0;
  }
  for (const auto& c : commands()) {
    if (std::string(argv[1]) == c.name) return c.main(argc - 1, argv + 1);
  }
  std::fprintf(stderr, "flume: unknown command '%s'\n", argv[1]);
  usage(stderr);
  return 2;
}
