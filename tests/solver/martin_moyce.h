// Martin & Moyce (1952), n^2 = 2: the surge front of a collapsing water column, for the MPM and SPH tests.
// The front Z = z/a against T = t sqrt(2g/a) is compared with Table 2 after one time shift (the experiment's
// gate opened with a lag).
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "solver/simulation.h"

namespace flume::test {

constexpr double kMmA = 0.05715;  // column width a (m); height 2a
constexpr double kMmG = 9.80665;

struct FrontCurve {
  std::vector<double> T, Z;
  double at(double t) const {
    if (t <= T.front()) return Z.front();
    auto it = std::lower_bound(T.begin(), T.end(), t);
    if (it == T.end()) return Z.back();
    const size_t i = it - T.begin();
    const double s = (t - T[i - 1]) / (T[i] - T[i - 1]);
    return Z[i - 1] + s * (Z[i] - Z[i - 1]);
  }
};

// Steps the simulation to its end, recording the front: the leading particle's edge, half a spacing ahead of
// it.
inline RunStatus record_front(Simulation& sim, double spacing, FrontCurve& c) {
  const double t_scale = std::sqrt(2 * kMmG / kMmA);
  std::vector<double> xyz;
  RunStatus status = RunStatus::kRunning;
  while (true) {
    sim.particle_positions(xyz);
    double front = 0;
    for (size_t i = 0; i < sim.particle_count(); ++i) front = std::max(front, xyz[3 * i]);
    c.T.push_back(sim.time() * t_scale);
    c.Z.push_back((front + 0.5 * spacing) / kMmA);
    if (status != RunStatus::kRunning) return status;
    status = sim.step();
  }
}

struct Fit {
  double rms, shift;
};
// Best single time shift dT in [lo, hi]: experiment at T compares with the simulation at T - dT.
inline Fit fit_shift(const FrontCurve& sim, const std::vector<std::vector<double>>& data, double lo = -0.2,
                     double hi = 0.2) {
  Fit best{1e300, 0};
  const int n_shifts = static_cast<int>(std::lround((hi - lo) / 0.005));
  for (int k = 0; k <= n_shifts; ++k) {
    const double dT = lo + (hi - lo) * k / n_shifts;
    double s = 0;
    int n = 0;
    for (const auto& r : data) {
      if (r[0] < 0.4 || r[0] > 3.0) continue;
      const double e = sim.at(r[0] - dT) - r[1];
      s += e * e;
      ++n;
    }
    const double rms = std::sqrt(s / n);
    if (rms < best.rms) best = {rms, dT};
  }
  return best;
}

// RMS difference of two fronts over 0.4 <= T <= 3.
inline double front_difference(const FrontCurve& a, const FrontCurve& b) {
  double s = 0;
  int n = 0;
  for (double T = 0.4; T <= 3.0; T += 0.05, ++n) s += std::pow(a.at(T) - b.at(T), 2);
  return std::sqrt(s / n);
}

}  // namespace flume::test
