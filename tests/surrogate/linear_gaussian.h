// The linear-Gaussian calibration problem the posterior tests share: y = 1 + 2 t at n times in [0, 1] plus
// N(0, sigma^2) noise (a fixed seed), and its analytic posterior under a flat prior on (a, b) of y = a + b t:
// Gaussian, with the least-squares mean and covariance sigma^2 (X^T X)^-1.
#pragma once
#include <cmath>
#include <random>
#include <vector>

namespace flume::test {

struct LinearGaussian {
  int n = 0;
  double sigma = 0;
  std::vector<double> t, y;
  double mean[2] = {0, 0}, sd[2] = {0, 0}, corr = 0;
};

inline LinearGaussian linear_gaussian(int n, double sigma) {
  LinearGaussian g;
  g.n = n;
  g.sigma = sigma;
  g.t.resize(n);
  g.y.resize(n);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0, sigma);
  for (int i = 0; i < n; ++i) {
    g.t[i] = i / (n - 1.0);
    g.y[i] = 1.0 + 2.0 * g.t[i] + noise(rng);
  }
  double st = 0, stt = 0, sy = 0, sty = 0;
  for (int i = 0; i < n; ++i) st += g.t[i], stt += g.t[i] * g.t[i], sy += g.y[i], sty += g.t[i] * g.y[i];
  const double det = n * stt - st * st;
  g.mean[0] = (stt * sy - st * sty) / det;
  g.mean[1] = (n * sty - st * sy) / det;
  g.sd[0] = sigma * std::sqrt(stt / det);
  g.sd[1] = sigma * std::sqrt(n / det);
  g.corr = -st / std::sqrt(n * stt);
  return g;
}

}  // namespace flume::test
