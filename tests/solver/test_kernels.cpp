// The shared physics functions (solver/mpm_kernels.h) against independent references.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "solver/mpm_kernels.h"

namespace {

using flume::mpm::tait_energy_density;
using flume::mpm::tait_pressure;

// References in long double through expm1l/log1pl, the closed forms the integer-exponent path replaces.
long double reference_pressure(long double e, long double K, long double g) {
  return K / g * std::expm1l(-g * std::log1pl(e));
}
// W = -(K/g) integral_0^e ((1+s)^-g - 1) ds, by Gauss-Legendre on 1024 panels: an independent route (no closed
// form, so no shared cancellation), exact to long double round-off for these smooth integrands.
long double reference_energy(long double e, long double K, long double g) {
  const long double xg[4] = {-0.8611363115940526L, -0.3399810435848563L, 0.3399810435848563L,
                             0.8611363115940526L};
  const long double wg[4] = {0.3478548451374538L, 0.6521451548625461L, 0.6521451548625461L,
                             0.3478548451374538L};
  const int panels = 1024;
  long double sum = 0;
  for (int k = 0; k < panels; ++k) {
    const long double a = e * k / panels, b = e * (k + 1) / panels;
    for (int q = 0; q < 4; ++q) {
      const long double s = 0.5L * (a + b) + 0.5L * (b - a) * xg[q];
      sum += 0.5L * (b - a) * wg[q] * std::expm1l(-g * std::log1pl(s));
    }
  }
  return -K / g * sum;
}

const double kStrains[] = {-0.5, -0.45, -0.1, -1e-2, -1e-3, -1e-4, -1e-6, -1e-8, 1e-8, 1e-6, 1e-4, 1e-3, 1e-2, 0.1, 0.5};
// 7.125 = 57/8 is the Waseda scenes' exponent; 7.1 and 40.3 are not m / 2^k (k <= 3) and take the libm path.
const double kGammas[] = {1.0, 2.0, 7.0, 7.1, 7.125, 7.5, 20.0, 20.5, 31.875, 40.3};

// Each path is a short chain of roundings (up to three halvings and a binary powering, or two libm calls), so the
// relative error is a small multiple of the precision's epsilon times the exponent. The energy's closed form,
// taken where the exponent is not m / 2^k (or is 1), sums terms of size K |e| / gamma to a result of size
// K e^2 / 2: its error is relative to K |e| where that exceeds the result.
bool exact_path(double g) {
  int k = 0;
  return g != 1.0 && flume::mpm::tait_dyadic_gamma(g, k) != 0;
}
template <typename T>
void check_pressure(double tol_eps) {
  const T K = T(2e6);
  for (double g : kGammas)
    for (double e : kStrains) {
      const long double ref = reference_pressure(static_cast<long double>(T(e)), K, g);
      const double got = double(tait_pressure(T(e), K, T(g)));
      const double tol = tol_eps * (g + 1) * std::numeric_limits<T>::epsilon() * double(std::fabs(ref));
      EXPECT_NEAR(got, double(ref), tol) << "gamma " << g << " e " << e;
    }
}
template <typename T>
void check_energy(double tol_eps) {
  const T K = T(2e6);
  for (double g : kGammas)
    for (double e : kStrains) {
      if (std::fabs(e) < 1e-6) continue;  // W ~ K e^2 / 2 underflows against the references' own error
      const long double ref = reference_energy(static_cast<long double>(T(e)), K, g);
      const double got = double(tait_energy_density(T(e), K, T(g)));
      const double scale = std::max(double(std::fabs(ref)), exact_path(g) ? 0.0 : double(K) * std::fabs(e));
      const double tol = tol_eps * (g + 1) * std::numeric_limits<T>::epsilon() * scale;
      EXPECT_NEAR(got, double(ref), tol) << "gamma " << g << " e " << e;
      EXPECT_GE(got, 0.0) << "the stored energy is non-negative";
    }
}

TEST(Tait, PressureMatchesTheClosedFormDouble) { check_pressure<double>(8); }
TEST(Tait, PressureMatchesTheClosedFormFloat) { check_pressure<float>(8); }
TEST(Tait, EnergyMatchesTheIntegralOfPressureDouble) { check_energy<double>(16); }

TEST(Tait, ExponentsOfTheFormMOver2kTakeTheExactPath) {
  int k = -1;
  EXPECT_EQ(flume::mpm::tait_dyadic_gamma(7.0, k), 7);
  EXPECT_EQ(k, 0);
  EXPECT_EQ(flume::mpm::tait_dyadic_gamma(7.125f, k), 57);
  EXPECT_EQ(k, 3);
  EXPECT_EQ(flume::mpm::tait_dyadic_gamma(20.5, k), 41);
  EXPECT_EQ(k, 1);
  EXPECT_EQ(flume::mpm::tait_dyadic_gamma(7.1, k), 0);
  EXPECT_EQ(flume::mpm::tait_dyadic_gamma(300.0, k), 0) << "m above kTaitMaxNumerator";
}

TEST(Tait, EnergyDerivativeIsMinusPressure) {
  // dW/dJ = -p, by central differences in long-double-free double: a check on the exact path's algebra.
  for (double g : {2.0, 7.0, 7.125, 20.0, 20.5})
    for (double e : {-0.05, -1e-3, 1e-3, 0.05}) {
      const double h = 1e-6 * std::fabs(e);
      const double dW = (tait_energy_density(e + h, 2e6, g) - tait_energy_density(e - h, 2e6, g)) / (2 * h);
      EXPECT_NEAR(dW, -tait_pressure(e, 2e6, g), 1e-6 * std::fabs(tait_pressure(e, 2e6, g)))
          << "gamma " << g << " e " << e;
    }
}

}  // namespace
