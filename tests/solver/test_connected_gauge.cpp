// The connected reading of a gauge (issue 30, solver/connected_depth.h), as a wire gauge reads: a still
// layer 5 cm deep with a block of water 4 cm high falling 10 cm above it (the splash of a breaking bore, its
// drops above the surface). Over the block the connected reading is the layer's depth and the volume
// reading, the default, is the layer and the block (9 cm); beside it both read the layer. Over the first 0.05 s
// (the block falls 1.2 cm: it stays 9 cm clear of the layer).
//
// Tolerance. The connected reading places the surface half a particle spacing above the top connected
// particle, which at rest is exact on the seeding lattice; the particles move by the column's compression
// (rho g h^2 / 2K = 0.06 mm here) and the solver's jitter, far under a spacing. The test allows a quarter
// of a cell (2.5 mm, half a particle spacing): a reading that counted the block, or stopped a layer short,
// is off by a spacing or more.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "common/errors.h"
#include "solver/scene.h"
#include "solver/simulation.h"
#include "test_util.h"

namespace flume {
namespace {

constexpr double kDx = 0.01, kLayer = 0.05, kBlock = 0.04;

std::string splash_scene(const std::string& method) {
  char text[4096];
  std::snprintf(text, sizeof text, R"({
    "name": "splash", "dimension": 2,
    "domain": {"lo": [-0.05, -0.05], "hi": [0.35, 0.3]},
    "solver": {"method": "%s", "dx": %g, "ppc": 4, "precision": "double", "end_time": 0.05},
    "fluid": {"bulk_modulus": 2.0e5, "gamma": 7.0, "viscosity": 1.0e-3, "jbar_psi": 0.9},
    "water": [{"lo": [0, 0], "hi": [0.3, %g], "hydrostatic": true},
              {"lo": [0.13, 0.15], "hi": [0.17, %g], "hydrostatic": false}],
    "boundaries": [
      {"name": "floor", "type": "half_space", "point": [0, 0], "normal": [0, 1], "condition": "slip"},
      {"name": "left", "type": "half_space", "point": [0, 0], "normal": [1, 0], "condition": "slip"},
      {"name": "right", "type": "half_space", "point": [0.3, 0], "normal": [-1, 0], "condition": "slip"}],
    "instruments": {"gauges": [
      {"name": "under_volume", "position": [0.15], "rate_hz": 200},
      {"name": "under_wire", "position": [0.15], "rate_hz": 200, "reading": "connected"},
      {"name": "beside_volume", "position": [0.06], "rate_hz": 200, "reading": "volume"},
      {"name": "beside_wire", "position": [0.06], "rate_hz": 200, "reading": "connected"}]}
  })",
                method.c_str(), kDx, kLayer, 0.15 + kBlock);
  return text;
}

void check_splash(const std::string& method) {
  const Scene scene = parse_scene_text(splash_scene(method), "splash.json");
  auto sim = make_simulation(scene, {Backend::kCpu, 1});
  ASSERT_EQ(test::run_until(*sim, scene.solver.end_time), RunStatus::kOk) << sim->message();
  const auto& g = sim->record().gauges;
  const double tol = 0.25 * kDx;
  double worst[4] = {0, 0, 0, 0};  // largest misfit of each gauge
  const char* names[4] = {"under_volume", "under_wire", "beside_volume", "beside_wire"};
  const double expect[4] = {kLayer + kBlock, kLayer, kLayer, kLayer};
  for (int k = 0; k < 4; ++k) {
    const TimeSeries& ts = g.at(names[k]);
    ASSERT_GE(ts.size(), 10u);
    for (size_t i = 0; i < ts.size(); ++i) worst[k] = std::max(worst[k], std::fabs(ts.at(i) - expect[k]));
    std::printf("%s %s: last %.4f m (expected %.4f), worst misfit %.2e m\n", method.c_str(), names[k],
                ts.at(ts.size() - 1), expect[k], worst[k]);
  }
  EXPECT_LT(worst[1], tol) << "the wire gauge reads the layer under the block";
  EXPECT_LT(worst[0], tol) << "the volume gauge counts the block over it";
  EXPECT_LT(worst[2], tol) << "both read the still layer";
  EXPECT_LT(worst[3], tol) << "both read the still layer";
  const TimeSeries &a = g.at("beside_volume"), &b = g.at("beside_wire");
  for (size_t i = 0; i < a.size(); ++i) EXPECT_LT(std::fabs(a.at(i) - b.at(i)), tol) << "t = " << a.time[i];
}

TEST(ConnectedGauge, SplashOverALayerMpm) { check_splash("mpm"); }
TEST(ConnectedGauge, SplashOverALayerSph) { check_splash("sph"); }

TEST(ConnectedGauge, BadReading) {
  std::string text = splash_scene("mpm");
  const std::string from = R"("reading": "connected")";
  text.replace(text.find(from), from.size(), R"("reading": "wire")");
  try {
    parse_scene_text(text, "bad_reading.json");
    ADD_FAILURE() << "accepted reading 'wire'";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("instruments.gauges.1.reading"), std::string::npos) << what;
    EXPECT_NE(what.find("volume|connected"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace flume
