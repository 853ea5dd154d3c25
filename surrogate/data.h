// What a surrogate is fitted to: one metric of a campaign's finished runs, with the campaign's input
// distributions, read once from the store into plain values.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "sampling/design.h"
#include "sampling/distribution.h"

namespace flume::surrogate {

struct TrainingData {
  std::string db_file;
  std::string campaign;
  std::int64_t campaign_id = 0;
  std::string metric;
  std::vector<std::string> inputs;                  // parameter paths, in design order
  std::vector<sampling::Distribution> distributions;  // one per input (a choice: over the index of its value)
  std::vector<sampling::RankCorrelation> correlations;
  // One entry per distinct ok run with a finite value of the metric, in design order.
  std::vector<std::int64_t> run_ids;
  std::vector<std::vector<double>> x;  // a choice parameter holds the index of its value
  std::vector<double> y;
  std::size_t runs_without_metric = 0;  // ok runs that lack it (reported, not fitted)
  // With a condition (`given`, a metric that exists only where an event happened, such as a gauge's arrival):
  // only runs where it exists are fitted, and the inputs of the ok runs outside it are kept for the classifier
  // of where it holds (surrogate/fit.h). Without one, the runs that lack the metric itself are "outside".
  std::string given;
  std::vector<std::vector<double>> x_outside;
  std::size_t outside_held_back = 0;  // the last ones of x_outside are held-back runs (--validation; with
                                      // --holdout every outside run trains the classifier)
};

// Throws flume::InputError naming the file and the option for an unknown campaign or metric (or condition), a
// campaign without parameters (a list design), or fewer than `min_runs` usable runs.
TrainingData load_training_data(const std::string& db_file, const std::string& campaign, const std::string& metric,
                                std::size_t min_runs = 4, const std::string& given = "");

// The index a stored parameter value has in its distribution's support (choices), or the value itself.
double design_value(const sampling::Distribution& d, bool is_text, double number, const std::string& text);

}  // namespace flume::surrogate
