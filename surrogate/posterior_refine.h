// The posterior's refinement, a sequential design for Bayesian calibration on an emulator: the emulator is
// only as good as the evaluations around the posterior's mass, and a calibration's evaluations follow the
// optimizer's path and the profiles' steps, which can leave the posterior's region between them unrun (the
// Waseda twin at 8 mm, docs/surrogates.md). Each round runs K draws of the current posterior as evaluations
// of the calibration (phase "refine", start = the round), so the next round's emulator knows the region the
// posterior claims. Round r's posterior uses the refinement's rounds before r only, so the same command
// again replays the same draws and finds their runs in the store.
#pragma once
#include <cstddef>
#include <string>

#include "surrogate/posterior.h"

namespace flume::surrogate {

struct RefineSettings {
  std::size_t points = 0;  // draws run per round; 0: no refinement
  int rounds = 1;
  int workers = 1;     // runs at once
  bool series = true;  // the series emulator, else the misfit surrogate
};

// Runs the rounds, printing one line of intervals per round. Returns 0, or the exit code of a stopped run.
int refine_posterior(const std::string& db_file, const std::string& calibration,
                     const PosteriorSettings& posterior, const RefineSettings& refine);

}  // namespace flume::surrogate
