// Adaptive designs: runs added one batch at a time where the kriging surrogate is least sure.
//   variance    the candidate with the largest kriging variance (maximum-variance sampling; Sacks et al. 1989)
//   exceedance  the candidate most likely to be on the wrong side of a threshold t: smallest
//               U = |mu - t| / sigma (AK-MCS, Echard, Gayton & Lemaire 2011)
// Candidates are a Monte Carlo sample of the input law. Within a batch, each pick is added to the kriging at
// its predicted value with the covariance kept ("kriging believer", Ginsbourger, Le Riche & Carraro 2010), so
// the variance there drops and the next pick goes elsewhere.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "surrogate/data.h"

namespace flume::surrogate {

enum class Criterion { kVariance, kExceedance };

struct AdaptiveSettings {
  Criterion criterion = Criterion::kVariance;
  double threshold = 0;          // exceedance: t
  std::size_t batch = 5;
  std::size_t candidates = 2000;
  std::uint64_t seed = 1;
};

struct Proposal {
  std::vector<std::vector<double>> points;  // design values, as TrainingData::x
  std::vector<double> score;                // variance, or U, of each pick when it was picked
};

// Deterministic in (data, settings): the candidates are seeded by settings.seed and the number of runs.
// `kriging_model`: a kriging already fitted to `data` (a stored surrogate's model); empty: fitted here.
Proposal propose_batch(const TrainingData& data, const AdaptiveSettings& settings,
                       const std::string& kriging_model = "");

}  // namespace flume::surrogate
