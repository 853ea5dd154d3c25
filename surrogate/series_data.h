// The gauge series of a calibration's stored evaluations, for the posterior on a series emulator
// (series_posterior.h): each evaluation's residuals, simulated minus target at every sample of the target
// records inside the objective's window, as `flume calibrate` computed its misfit (calibration::Objective on
// the run's result.h5).
#pragma once
#include <string>
#include <vector>

#include "surrogate/posterior.h"

namespace flume::surrogate {

struct SeriesData : CalibrationBox {
  std::vector<std::vector<double>> points;  // parameter values of each evaluation, `names` order
  std::vector<std::vector<double>>
      residuals;           // sqrt(w_g) (sim - target) per window sample, gauges in order, m
  double n_residuals = 0;  // sum_g w_g n_g: SSR / n_residuals is the stored RMS^2
};

// The refinement's evaluations of rounds before `rounds_before` only. Failed evaluations are left out, and a
// point evaluated twice counts once. Throws flume::InputError naming the file for an unknown calibration, a
// target record changed since, a run whose result.h5 is gone or no longer gives the misfit the store has for
// it, or too few evaluations.
SeriesData load_calibration_series(const std::string& db_file, const std::string& name,
                                   int rounds_before = kAllRounds);

}  // namespace flume::surrogate
