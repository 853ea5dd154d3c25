// Contact physics of the debris boxes against theory (issue 4, tests 1, 2 and 4), on the Waseda container
// (0.15 x 0.06 x 0.06 m, 0.226 kg) with coefficients from the paper's Table 2 ranges.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "solver/rigid/rigid_world.h"

namespace flume {
namespace {

constexpr double kG = 9.80665;
constexpr double kPi = 3.14159265358979323846;
const Eigen::Vector3d kGravity(0, 0, -kG);

// The Waseda container with its long side (body x) across the flow (world y), on top of any extra rotation.
RigidBoxSpec container(const std::string& name, const Eigen::Vector3d& centre,
                       const Eigen::Quaterniond& tilt = Eigen::Quaterniond::Identity()) {
  RigidBoxSpec s;
  s.name = name;
  s.size = Eigen::Vector3d(0.15, 0.06, 0.06);
  s.mass = 0.226;
  s.position = centre;
  s.orientation = tilt * Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()));
  return s;
}

ContactCoefficients coefficients(double mu_flume, double mu_debris, double e_flume, double e_debris) {
  ContactCoefficients c;
  c.friction_flume = mu_flume;
  c.friction_debris = mu_debris;
  c.restitution_flume = e_flume;
  c.restitution_debris = e_debris;
  return c;
}

// ---- Test 1: a box on a dry incline -------------------------------------------------------------------------
// The incline is the half-space below the plane through the origin with normal (-sin t, 0, cos t); downhill is
// (-cos t, 0, -sin t). Coulomb: the box sticks when tan t < mu, else slides with a = g (sin t - mu cos t).
struct InclineRun {
  double displacement;  // along the slope, downhill positive, after `duration`
  double acceleration;  // downhill, from the velocity change between 0.1 s and `duration`
};

InclineRun run_incline(double theta, double mu, double duration, double dt) {
  RigidWorld world(coefficients(mu, 0.4, 0.45, 0.55), kGravity);
  const Eigen::Vector3d n(-std::sin(theta), 0, std::cos(theta));
  const Eigen::Vector3d down(-std::cos(theta), 0, -std::sin(theta));
  world.add_static_half_space(Eigen::Vector3d::Zero(), n);
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(-theta, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d start = 0.03 * n;
  const int body = world.add_box(container("D1", start, tilt));
  const int steps = int(std::lround(duration / dt));
  const int early = int(std::lround(0.1 / dt));
  double v_early = 0;
  for (int k = 1; k <= steps; ++k) {
    world.step(dt);
    if (k == early) v_early = world.state(body).velocity.dot(down);
  }
  const BodyState s = world.state(body);
  return {(s.position - start).dot(down), (s.velocity.dot(down) - v_early) / (duration - 0.1)};
}

struct SlideCase {
  double mu, theta_deg, dt;
};
class InclineSlides : public ::testing::TestWithParam<SlideCase> {};

TEST_P(InclineSlides, AccelerationIsCoulombWithin2Percent) {
  const SlideCase c = GetParam();
  const double theta = c.theta_deg * kPi / 180;
  ASSERT_GT(std::tan(theta), c.mu);
  const double expected = kG * (std::sin(theta) - c.mu * std::cos(theta));
  const InclineRun r = run_incline(theta, c.mu, 0.6, c.dt);
  std::printf("incline mu=%.2f theta=%.1f dt=%.0e: a=%.5f expected %.5f (%.3f%%)\n", c.mu, c.theta_deg, c.dt,
              r.acceleration, expected, 100 * (r.acceleration / expected - 1));
  EXPECT_NEAR(r.acceleration, expected, 0.02 * expected);
}

INSTANTIATE_TEST_SUITE_P(Table2Friction, InclineSlides,
                         ::testing::Values(SlideCase{0.15, 20.0, 1e-4}, SlideCase{0.30, 30.0, 1e-4},
                                           SlideCase{0.50, 35.0, 1e-3}, SlideCase{0.80, 42.0, 1e-4},
                                           SlideCase{0.30, 30.0, 1e-5},
                                           // just past the limit: tan(theta) = 1.1 mu
                                           SlideCase{0.50, 28.810793, 1e-4}));

struct StickCase {
  double mu, tan_ratio, dt;
};
class InclineSticks : public ::testing::TestWithParam<StickCase> {};

TEST_P(InclineSticks, BoxStaysPut) {
  const StickCase c = GetParam();
  const double theta = std::atan(c.tan_ratio * c.mu);
  const InclineRun r = run_incline(theta, c.mu, 2.0, c.dt);
  std::printf("incline mu=%.2f tan=%.2f mu dt=%.0e: creep %.3e m in 2 s\n", c.mu, c.tan_ratio, c.dt,
              r.displacement);
  // Sticking means no sliding: under 1 mm in 2 s (the creep bound of test 4). Sliding at the smallest
  // Coulomb acceleration in these cases would cover > 10 cm.
  EXPECT_LT(std::abs(r.displacement), 1e-3);
}

INSTANTIATE_TEST_SUITE_P(Table2Friction, InclineSticks,
                         ::testing::Values(StickCase{0.15, 0.9, 1e-4}, StickCase{0.50, 0.9, 1e-3},
                                           StickCase{0.80, 0.9, 1e-4}, StickCase{0.50, 0.5, 1e-4}));

// ---- Test 2a: drop on the floor ---------------------------------------------------------------------------
// A box dropped flat from rest, bottom at height h, rebounds to e^2 h (e: flume-debris restitution).
double rebound_ratio(double e, double h, double dt) {
  RigidWorld world(coefficients(0.5, 0.4, e, 0.55), kGravity);
  world.add_static_half_space(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  const int body = world.add_box(container("D1", Eigen::Vector3d(4.65, 0, 0.03 + h)));
  bool bounced = false;
  double apex = 0;
  for (int k = 0; k < int(2.0 / dt); ++k) {
    world.step(dt);
    const BodyState s = world.state(body);
    if (!bounced && s.velocity.z() > 0) bounced = true;
    if (bounced) {
      apex = std::max(apex, s.position.z() - 0.03);
      if (s.velocity.z() < 0) break;
    }
  }
  EXPECT_TRUE(bounced);
  return apex / h;
}

struct DropCase {
  double e, dt;
};
class Drop : public ::testing::TestWithParam<DropCase> {};

TEST_P(Drop, ReboundsToESquaredHeightWithin5Percent) {
  const DropCase c = GetParam();
  const double h = 0.1;
  const double ratio = rebound_ratio(c.e, h, c.dt);
  std::printf("drop e=%.2f dt=%.0e: rebound/h = %.5f expected %.5f (%.3f%%)\n", c.e, c.dt, ratio, c.e * c.e,
              100 * (ratio / (c.e * c.e) - 1));
  EXPECT_NEAR(ratio, c.e * c.e, 0.05 * c.e * c.e);
}

INSTANTIATE_TEST_SUITE_P(Restitution, Drop,
                         ::testing::Values(DropCase{0.3, 1e-4}, DropCase{0.6, 1e-4}, DropCase{0.9, 1e-4},
                                           DropCase{0.3, 1e-3}, DropCase{0.6, 1e-5}, DropCase{0.9, 1e-3},
                                           DropCase{0.45, 1e-6}));

// ---- Test 2b: head-on collision -----------------------------------------------------------------------------
// Two containers face to face, no gravity; the relative normal speed after/before is the debris-debris e.
struct CollisionResult {
  double ratio, momentum_error;
};
CollisionResult collide(double e, double v0, double dt) {
  RigidWorld world(coefficients(0.5, 0.4, 0.45, e), Eigen::Vector3d::Zero());
  RigidBoxSpec a = container("D1", Eigen::Vector3d(4.65, 0, 0.5));
  RigidBoxSpec b = container("D2", Eigen::Vector3d(4.75, 0, 0.5));
  a.velocity = Eigen::Vector3d(v0, 0, 0);
  const int ia = world.add_box(a), ib = world.add_box(b);
  for (int k = 0; k < int(0.2 / dt); ++k) world.step(dt);
  const BodyState sa = world.state(ia), sb = world.state(ib);
  const double p = 0.226 * (sa.velocity.x() + sb.velocity.x());
  return {(sb.velocity.x() - sa.velocity.x()) / v0, std::abs(p - 0.226 * v0) / (0.226 * v0)};
}

struct CollisionCase {
  double e, v0, dt;
};
class HeadOn : public ::testing::TestWithParam<CollisionCase> {};

TEST_P(HeadOn, RelativeSpeedRatioIsEWithin5Percent) {
  const CollisionCase c = GetParam();
  const CollisionResult r = collide(c.e, c.v0, c.dt);
  std::printf("collision e=%.2f v0=%.2f dt=%.0e: ratio %.5f (%.3f%%), momentum error %.1e\n", c.e, c.v0, c.dt,
              r.ratio, 100 * (r.ratio / c.e - 1), r.momentum_error);
  EXPECT_NEAR(r.ratio, c.e, 0.05 * c.e);
  EXPECT_LT(r.momentum_error, 1e-9);  // contact impulses are equal and opposite
}

INSTANTIATE_TEST_SUITE_P(Restitution, HeadOn,
                         ::testing::Values(CollisionCase{0.3, 1.0, 1e-4}, CollisionCase{0.6, 1.0, 1e-4},
                                           CollisionCase{0.9, 1.0, 1e-4}, CollisionCase{0.4, 0.5, 1e-3},
                                           CollisionCase{0.7, 2.0, 1e-5}));

// ---- Test 4: two-layer stack at rest on a dry apron -------------------------------------------------------
// Three containers side by side across the flume, 0.03 m apart, and three more on top, on an apron (a static
// box) beside a floor; 5 s at rest must move no box more than 1 mm.
double stack_creep(double mu_flume, double mu_debris, double dt, double duration) {
  RigidWorld world(coefficients(mu_flume, mu_debris, 0.45, 0.55), kGravity);
  world.add_static_half_space(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  const double apron_top = 0.10;
  world.add_static_box(Eigen::Vector3d(4.0, -0.6, 0.0), Eigen::Vector3d(6.0, 0.6, apron_top));
  std::vector<Eigen::Vector3d> start;
  for (int layer = 0; layer < 2; ++layer)
    for (int j = -1; j <= 1; ++j) {
      const Eigen::Vector3d c(4.65 + 0.03, j * (0.15 + 0.03), apron_top + 0.03 + 0.06 * layer);
      world.add_box(container("D" + std::to_string(start.size() + 1), c));
      start.push_back(c);
    }
  const int steps = int(std::lround(duration / dt));
  for (int k = 0; k < steps; ++k) world.step(dt);
  double creep = 0;
  for (int i = 0; i < world.body_count(); ++i)
    creep = std::max(creep, (world.state(i).position - start[i]).norm());
  return creep;
}

struct StackCase {
  double mu_flume, mu_debris, dt, duration;
};
class Stack : public ::testing::TestWithParam<StackCase> {};

TEST_P(Stack, StaysPutWithin1mm) {
  const StackCase c = GetParam();
  const double creep = stack_creep(c.mu_flume, c.mu_debris, c.dt, c.duration);
  std::printf("stack mu=%.2f/%.2f dt=%.0e %.0f s: creep %.3e m\n", c.mu_flume, c.mu_debris, c.dt, c.duration,
              creep);
  EXPECT_LT(creep, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(Table2Friction, Stack,
                         ::testing::Values(StackCase{0.15, 0.05, 1e-4, 5.0}, StackCase{0.80, 0.80, 1e-3, 5.0},
                                           StackCase{0.40, 0.40, 2e-5, 1.0}));

}  // namespace
}  // namespace flume
