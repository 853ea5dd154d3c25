// Experimental designs over a campaign's parameters. Every design is built by OpenTURNS (MonteCarloExperiment,
// LHSExperiment, LowDiscrepancyExperiment + SobolSequence, Box, Axial, SobolIndicesExperiment) on the unit cube
// and mapped to the parameters' joint distribution by OpenTURNS' inverse iso-probabilistic transformation.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sampling/distribution.h"

namespace flume::sampling {

enum class DesignType {
  kMonteCarlo,      // independent draws
  kLatinHypercube,  // one point per equal-probability stratum of every parameter
  kSobol,           // randomised (random-shift) Sobol' quasi-Monte Carlo
  kGrid,            // full factorial over equal-probability stratum midpoints
  kOneAtATime,      // the median point, then each parameter moved alone
  kSaltelli,        // pick-freeze design for Sobol' indices: N * (d + 2) points
};

const char* to_string(DesignType t);

struct DesignSpec {
  DesignType type = DesignType::kMonteCarlo;
  size_t samples = 0;  // points (MC, LHS, Sobol'); base size N (Saltelli); unused by grid/one-at-a-time
  size_t levels = 0;   // grid: points per continuous parameter (0: from samples); one-at-a-time: steps per side
  DesignType saltelli_base = DesignType::kMonteCarlo;  // the experiment the Saltelli A and B matrices come from
};

// Spearman (rank) correlation between parameters a and b, imposed through a normal copula.
struct RankCorrelation {
  size_t a = 0, b = 0;
  double rho = 0.0;
};

struct Design {
  // Points in the unit cube (probabilities), before the map to the distributions; row = point.
  std::vector<std::vector<double>> unit;
  // Parameter values per point; a choice parameter holds the index of its value.
  std::vector<std::vector<double>> values;
  // Saltelli: N, with rows ordered A (N rows), B (N rows), then A with column i from B for i = 0..d-1,
  // as OpenTURNS' SobolIndicesExperiment and SaltelliSensitivityAlgorithm expect. 0 otherwise.
  size_t saltelli_base_size = 0;
};

// Throws std::invalid_argument (with a one-line reason) for an impossible design, e.g. a correlation matrix
// that is not positive definite or a design with no points.
Design generate_design(const std::vector<Distribution>& parameters, const std::vector<RankCorrelation>& correlations,
                       const DesignSpec& spec, std::uint64_t seed);

// Number of points generate_design will return (for messages and progress before generating).
size_t design_size(const std::vector<Distribution>& parameters, const DesignSpec& spec);

// Centred L2 discrepancy (Hickernell) of points in the unit cube, by OpenTURNS' SpaceFillingC2.
double centred_l2_discrepancy(const std::vector<std::vector<double>>& unit_points);

}  // namespace flume::sampling
