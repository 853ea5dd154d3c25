// Martin & Moyce (1952), n^2 = 2: the surge front of a collapsing water column (issue 2, item 2), compared
// with Table 2 (martin_moyce.h); the front must converge as dx is refined.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "common/plot/figure.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "martin_moyce.h"
#include "test_util.h"

namespace flume {
namespace {

using test::FrontCurve;
using test::Fit;
using test::fit_shift;
constexpr double kA = test::kMmA;

// Runs the shipped scene at resolution dx and records the front (the leading particle's edge) over time.
FrontCurve simulate_front(double dx) {
  const Scene scene = load_scene(std::string(FLUME_SOURCE_DIR) + "/scenes/dam_break/martin_moyce_2d.json",
                                 {{"solver.dx", std::to_string(dx)}, {"instruments.snapshot_rate_hz", "0"}});
  auto sim = make_simulation(scene, {});
  FrontCurve c;
  const RunStatus status = test::record_front(*sim, dx / 2, c);  // ppc 4: two particles per cell per axis
  EXPECT_EQ(status, RunStatus::kOk) << sim->message();
  EXPECT_NEAR(c.T.back(), scene.solver.end_time * std::sqrt(2 * test::kMmG / kA), 1e-9);
  return c;
}

TEST(MartinMoyce, FrontMatchesTable2AndConverges) {
  const auto data =
      test::read_csv(test::validation_file("martin_moyce_1952/mm1952_table2_n2sq2_a2.25in_front.csv"));
  ASSERT_GE(data.size(), 10u) << "Martin & Moyce Table 2 not found";
  const double dxs[3] = {kA / 10, kA / 20, kA / 40};
  FrontCurve curves[3];
  for (int k = 0; k < 3; ++k) {
    curves[k] = simulate_front(dxs[k]);
    const Fit f = fit_shift(curves[k], data);
    // The unconstrained best shift is reported too: it measures the experiment's gate lag.
    const Fit free_fit = fit_shift(curves[k], data, -1.0, 1.0);
    std::printf("dx = a/%d: RMS(Z) = %.4f after shift dT = %+.3f (best unconstrained: %.4f at %+.3f)\n", 10 << k,
                f.rms, f.shift, free_fit.rms, free_fit.shift);
  }
  const Fit fine = fit_shift(curves[2], data);
  EXPECT_LE(fine.rms, 0.15) << "front RMS error against Martin & Moyce Table 2";
  EXPECT_LE(std::fabs(fine.shift), 0.2);
  // Convergence: the difference between successive resolutions shrinks (sampled over 0.4 <= T <= 3).
  const double d01 = test::front_difference(curves[0], curves[1]);
  const double d12 = test::front_difference(curves[1], curves[2]);
  std::printf("successive differences: |a/10 - a/20| = %.4f, |a/20 - a/40| = %.4f\n", d01, d12);
  EXPECT_LT(d12, d01);

  // FLUME_PLOT_DIR=DIR: the three fronts, shifted by the fitted dT, against Table 2 (docs/validation.md).
  if (const char* dir = std::getenv("FLUME_PLOT_DIR")) {
    plot::Figure fig;
    auto& ax = fig.axes().title("Martin & Moyce (1952), n^2 = 2: surge front").xlabel("T = t sqrt(2g/a)");
    ax.ylabel("Z = z / a").xlim(0, 3.2);
    std::vector<double> tx, zx;
    for (const auto& r : data) {
      tx.push_back(r[0]);
      zx.push_back(r[1]);
    }
    for (int k = 0; k < 3; ++k) {
      const Fit f = fit_shift(curves[k], data);
      std::vector<double> T;
      for (double t : curves[k].T) T.push_back(t + f.shift);
      char label[64];
      std::snprintf(label, sizeof label, "flume dx = a/%d, dT = %+.2f", 10 << k, f.shift);
      ax.line(T, curves[k].Z, {.color = plot::palette(k), .label = label});
    }
    ax.scatter(tx, zx, {.color = plot::Color{0, 0, 0}, .label = "Martin & Moyce Table 2"});
    ax.legend(plot::Legend::kUpperLeft);
    fig.save(std::string(dir) + "/martin_moyce_1952.svg");
  }
}

}  // namespace
}  // namespace flume
