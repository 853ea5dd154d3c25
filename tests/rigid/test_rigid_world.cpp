// RigidWorld's coupling hooks (geometry queries, external loads, substepping), the pair coefficients, input
// checks and the DebrisRecorder, against closed-form answers.
#include <gtest/gtest.h>

#include <cmath>

#include "common/errors.h"
#include "solver/rigid/debris_recorder.h"
#include "solver/rigid/rigid_world.h"

namespace flume {
namespace {

constexpr double kG = 9.80665;
constexpr double kPi = 3.14159265358979323846;

RigidBoxSpec box(const std::string& name, const Eigen::Vector3d& size, double mass, const Eigen::Vector3d& centre) {
  RigidBoxSpec s;
  s.name = name;
  s.size = size;
  s.mass = mass;
  s.position = centre;
  return s;
}

// ---- geometry queries -------------------------------------------------------------------------------------

class Geometry : public ::testing::Test {
 protected:
  // A 0.2 x 0.1 x 0.06 box at c, turned 90 degrees about z: its long body x axis lies along world y.
  void SetUp() override {
    RigidBoxSpec s = box("B", Eigen::Vector3d(0.2, 0.1, 0.06), 1.0, c);
    s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()));
    s.velocity = Eigen::Vector3d(1, 2, 3);
    s.angular_velocity = Eigen::Vector3d(0, 0, 4);
    body = world.add_box(s);
  }
  RigidWorld world{ContactCoefficients{}, Eigen::Vector3d::Zero()};
  Eigen::Vector3d c{1.0, 2.0, 0.5};
  int body = -1;
};

TEST_F(Geometry, SignedDistanceIsEuclideanAndNegativeInside) {
  // World half-extents are (0.05, 0.1, 0.03) after the turn.
  EXPECT_NEAR(world.signed_distance(body, c), -0.03, 1e-12);                                   // nearest: z faces
  EXPECT_NEAR(world.signed_distance(body, c + Eigen::Vector3d(0.08, 0, 0)), 0.03, 1e-12);      // off the x face
  EXPECT_NEAR(world.signed_distance(body, c + Eigen::Vector3d(0, 0.09, 0)), -0.01, 1e-12);     // inside, near y face
  EXPECT_NEAR(world.signed_distance(body, c + Eigen::Vector3d(0.08, 0.14, 0)), 0.05, 1e-12);   // off an edge: 3-4-5
  EXPECT_NEAR(world.signed_distance(body, c + Eigen::Vector3d(0.05, 0.1, 0.03)), 0.0, 1e-12);  // a corner
}

TEST_F(Geometry, NormalIsTheDistanceGradient) {
  EXPECT_TRUE(world.outward_normal(body, c + Eigen::Vector3d(0.08, 0, 0)).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE(world.outward_normal(body, c + Eigen::Vector3d(0, -0.09, 0)).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE(world.outward_normal(body, c + Eigen::Vector3d(0.08, 0.14, 0)).isApprox(Eigen::Vector3d(0.6, 0.8, 0), 1e-12));
  // Finite differences of the distance agree with the normal at a generic outside point.
  const Eigen::Vector3d p = c + Eigen::Vector3d(0.07, -0.13, 0.05);
  Eigen::Vector3d fd;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[a] = 1e-6;
    fd[a] = (world.signed_distance(body, p + e) - world.signed_distance(body, p - e)) / 2e-6;
  }
  EXPECT_TRUE(fd.isApprox(world.outward_normal(body, p), 1e-6));
}

TEST_F(Geometry, SurfaceVelocityIsRigidMotion) {
  const Eigen::Vector3d r(0.05, -0.1, 0.03);
  const Eigen::Vector3d expected = Eigen::Vector3d(1, 2, 3) + Eigen::Vector3d(0, 0, 4).cross(r);
  EXPECT_TRUE(world.surface_velocity(body, c + r).isApprox(expected, 1e-12));
  // The POD view the GPU gets gives the same numbers.
  const RigidBoxView& v = world.box_views().at(body);
  double p[3] = {c.x() + r.x(), c.y() + r.y(), c.z() + r.z()}, u[3];
  box_surface_velocity(v, p, u);
  EXPECT_TRUE(Eigen::Vector3d(u[0], u[1], u[2]).isApprox(expected, 1e-12));
}

// ---- external loads and substepping -----------------------------------------------------------------------

TEST(Loads, ForceAndTorqueGiveNewtonEulerAccelerations) {
  RigidWorld world(ContactCoefficients{}, Eigen::Vector3d::Zero());
  const Eigen::Vector3d size(0.15, 0.06, 0.06);
  const double m = 0.226;
  const int b = world.add_box(box("D1", size, m, Eigen::Vector3d(0, 0, 1)));
  const Eigen::Vector3d f(0.3, -0.2, 0.5), tau(0, 0, 2e-4);
  world.apply_external(b, f, tau);
  world.step(1e-3);  // 10 substeps: the load acts on each
  const BodyState s = world.state(b);
  EXPECT_TRUE(s.acceleration.isApprox(f / m, 1e-12));
  const double izz = m * (size.x() * size.x() + size.y() * size.y()) / 12.0;  // cuboid about its centre
  EXPECT_NEAR(s.angular_acceleration.z(), tau.z() / izz, 1e-9 * tau.z() / izz);
  EXPECT_TRUE(s.velocity.isApprox(f / m * 1e-3, 1e-12));
  // The load is cleared after the step.
  world.step(1e-3);
  EXPECT_LT(world.state(b).acceleration.norm(), 1e-12);
}

TEST(Loads, ForceAtAPointAddsItsMoment) {
  RigidWorld world(ContactCoefficients{}, Eigen::Vector3d::Zero());
  const int b = world.add_box(box("D1", Eigen::Vector3d(0.1, 0.1, 0.1), 1.0, Eigen::Vector3d(0, 0, 1)));
  world.apply_force_at(b, Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0.05, 0, 1));  // torque (0, 0, 0.05)
  world.step(1e-4);
  const double izz = 1.0 * (0.01 + 0.01) / 12.0;
  EXPECT_NEAR(world.state(b).angular_acceleration.z(), 0.05 / izz, 1e-9);
  EXPECT_NEAR(world.state(b).acceleration.y(), 1.0, 1e-12);
}

TEST(Substeps, FreeFallMatchesGravityForAnyStep) {
  for (const double dt : {1e-6, 1e-5, 1e-4, 1e-3}) {
    RigidWorld world(ContactCoefficients{}, Eigen::Vector3d(0, 0, -kG));
    const int b = world.add_box(box("D1", Eigen::Vector3d(0.15, 0.06, 0.06), 0.226, Eigen::Vector3d(0, 0, 1)));
    const int n = int(std::lround(0.01 / dt));
    for (int k = 0; k < n; ++k) world.step(dt);
    const double t = world.time();
    EXPECT_NEAR(t, 0.01, 1e-12);
    EXPECT_NEAR(world.state(b).velocity.z(), -kG * t, 1e-12);
    // Symplectic Euler with substep h <= 1e-4 s: z = 1 - g t^2 / 2 - g t h / 2.
    EXPECT_NEAR(world.state(b).position.z(), 1 - 0.5 * kG * t * t, 0.5 * kG * t * std::min(dt, 1e-4) * 1.0001);
    EXPECT_NEAR(world.state(b).acceleration.z(), -kG, 1e-9);
  }
}

// ---- flume-debris vs debris-debris coefficients -------------------------------------------------------------

// A box launched along a surface decelerates at mu g: on the floor with mu_flume, on top of a heavy box (which
// itself rests on the floor) with mu_debris. The product rule would give mu_flume * mu_debris on the floor.
double sliding_deceleration(bool on_debris) {
  ContactCoefficients c;
  c.friction_flume = 0.6;
  c.friction_debris = 0.2;
  RigidWorld world(c, Eigen::Vector3d(0, 0, -kG));
  world.add_static_half_space(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  double base = 0;
  if (on_debris) {
    world.add_box(box("base", Eigen::Vector3d(2.0, 0.5, 0.1), 1000.0, Eigen::Vector3d(0.5, 0, 0.05)));
    base = 0.1;
  }
  RigidBoxSpec s = box("D1", Eigen::Vector3d(0.06, 0.15, 0.06), 0.226, Eigen::Vector3d(0, 0, base + 0.03));
  s.velocity = Eigen::Vector3d(1.0, 0, 0);
  const int b = world.add_box(s);
  const double dt = 1e-4;
  for (int k = 0; k < 1000; ++k) world.step(dt);
  return (1.0 - world.state(b).velocity.x()) / world.time();
}

TEST(PairCoefficients, FrictionIsChosenByPairKind) {
  const double floor = sliding_deceleration(false), debris = sliding_deceleration(true);
  std::printf("sliding deceleration: floor %.5f (expected %.5f), debris %.5f (expected %.5f)\n", floor, 0.6 * kG,
              debris, 0.2 * kG);
  EXPECT_NEAR(floor, 0.6 * kG, 0.02 * 0.6 * kG);
  EXPECT_NEAR(debris, 0.2 * kG, 0.02 * 0.2 * kG);
}

// A box dropped on a heavy resting box rebounds with the debris-debris e, on the floor with the flume e.
double drop_ratio(bool on_debris, double h) {
  ContactCoefficients c;
  c.restitution_flume = 0.35;
  c.restitution_debris = 0.65;
  RigidWorld world(c, Eigen::Vector3d(0, 0, -kG));
  world.add_static_half_space(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  double base = 0;
  if (on_debris) {
    world.add_box(box("base", Eigen::Vector3d(0.5, 0.5, 0.1), 1000.0, Eigen::Vector3d(0, 0, 0.05)));
    base = 0.1;
  }
  const int b = world.add_box(box("D1", Eigen::Vector3d(0.06, 0.15, 0.06), 0.226, Eigen::Vector3d(0, 0, base + 0.03 + h)));
  bool up = false;
  double apex = 0;
  for (int k = 0; k < 20000; ++k) {
    world.step(1e-4);
    const BodyState s = world.state(b);
    if (s.velocity.z() > 0) up = true;
    if (up) {
      apex = std::max(apex, s.position.z() - base - 0.03);
      if (s.velocity.z() < 0) break;
    }
  }
  return apex / h;
}

TEST(PairCoefficients, RestitutionIsChosenByPairKind) {
  const double floor = drop_ratio(false, 0.1), debris = drop_ratio(true, 0.1);
  std::printf("rebound/h: floor %.5f (expected %.5f), debris %.5f (expected %.5f)\n", floor, 0.35 * 0.35, debris,
              0.65 * 0.65);
  EXPECT_NEAR(floor, 0.35 * 0.35, 0.05 * 0.35 * 0.35);
  EXPECT_NEAR(debris, 0.65 * 0.65, 0.05 * 0.65 * 0.65);
}

// ---- input checks ----------------------------------------------------------------------------------------

TEST(Input, BadSpecsAreRejectedWithTheirField) {
  RigidWorld world(ContactCoefficients{}, Eigen::Vector3d(0, 0, -kG));
  RigidBoxSpec s = box("D1", Eigen::Vector3d(0.15, 0, 0.06), 0.226, Eigen::Vector3d::Zero());
  try {
    world.add_box(s);
    FAIL() << "zero edge accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "debris.D1.size");
  }
  s.size = Eigen::Vector3d(0.15, 0.06, 0.06);
  s.mass = 0;
  EXPECT_THROW(world.add_box(s), InputError);
  s.density = 418.5;  // kg/m^3: the Waseda container's mass from its density
  const int b = world.add_box(s);
  EXPECT_NEAR(world.mass(b), 418.5 * 0.15 * 0.06 * 0.06, 1e-12);
  s.position.x() = 1;
  EXPECT_THROW(world.add_box(s), InputError);  // duplicate name
  ContactCoefficients bad;
  bad.restitution_debris = 1.2;
  EXPECT_THROW(RigidWorld(bad, Eigen::Vector3d::Zero()), InputError);
  EXPECT_THROW(world.step(0.0), std::invalid_argument);
}

TEST(Input, SceneShapesBecomeBoundaries) {
  RigidWorld world(ContactCoefficients{}, Eigen::Vector3d(0, 0, -kG));
  Shape floor;
  floor.type = ShapeType::kHalfSpace;
  floor.point = {0, 0, 0.2};
  floor.normal = {0, 0, 2};  // not unit: normalised
  world.add_static_shape(floor);
  const int b = world.add_box(box("D1", Eigen::Vector3d(0.06, 0.15, 0.06), 0.226, Eigen::Vector3d(0, 0, 0.3)));
  for (int k = 0; k < 5000; ++k) world.step(1e-4);
  EXPECT_NEAR(world.state(b).position.z(), 0.23, 1e-5);  // at rest on the plane z = 0.2
}

// ---- recorder ---------------------------------------------------------------------------------------------

TEST(Recorder, ResamplesAt30HzWithWindowMeanAcceleration) {
  RigidWorld world(ContactCoefficients{}, Eigen::Vector3d(0, 0, -kG));
  const double m = 0.226;
  const int b = world.add_box(box("D1", Eigen::Vector3d(0.15, 0.06, 0.06), m, Eigen::Vector3d(0, 0, 10)));
  DebrisRecorder rec(world);
  const double dt = 1e-4, fx = 0.5;
  rec.record();
  for (int k = 0; k < 5000; ++k) {  // 0.5 s of free fall, with a 10 ms push along x from t = 0.1 s
    if (k >= 1000 && k < 1100) world.apply_external(b, Eigen::Vector3d(fx, 0, 0), Eigen::Vector3d::Zero());
    world.step(dt);
    rec.record();
  }
  rec.finish();
  EXPECT_EQ(rec.name(0), "D1");
  const DebrisSeries& fast = rec.solver_rate(0);
  ASSERT_EQ(fast.size(), 5001u);
  EXPECT_NEAR(fast.acceleration[1050][0], fx / m, 1e-9);
  EXPECT_NEAR(fast.force[1050][0], fx, 1e-9);
  EXPECT_NEAR(fast.force[2000][2], -m * kG, 1e-9);

  const DebrisSeries& slow = rec.resampled(0);
  ASSERT_EQ(slow.size(), 16u);  // t = 0, 1/30, ..., 15/30 = 0.5 s
  const double T = 1.0 / 30.0;
  for (size_t k = 0; k < slow.size(); ++k) {
    const double t = k * T;
    EXPECT_NEAR(slow.time[k], t, 1e-12);
    // Free fall is exact in the Hermite interpolation up to the integrator's g t h / 2 offset; between two
    // steps the interpolant adds at most g h^2 / 4 more (semi-implicit Euler's positions run h/2 ahead of
    // its velocities, which the Hermite cubic takes as exact slopes).
    EXPECT_NEAR(slow.position[k][2], 10 - 0.5 * kG * t * t, 0.5 * kG * t * dt + 0.25 * kG * dt * dt);
    EXPECT_NEAR(slow.velocity[k][2], -kG * t, 1e-9);
    EXPECT_NEAR(slow.acceleration[k][2], -kG, 1e-9);
    // A free-falling accelerometer reads nothing along z.
    EXPECT_NEAR(slow.specific_force_body[k][2], 0.0, 1e-9);
  }
  // The push (impulse fx * 0.01 s) lies wholly inside the window of sample 3, [0.0833, 0.1167] s.
  EXPECT_NEAR(slow.acceleration[3][0], fx * 0.01 / m / T, 1e-9);
  EXPECT_NEAR(slow.force[3][0], fx * 0.01 / T, 1e-9);
  EXPECT_NEAR(slow.acceleration[5][0], 0.0, 1e-9);
}

TEST(Recorder, AccelerometerAtRestReadsGravityUp) {
  RigidWorld world(ContactCoefficients{}, Eigen::Vector3d(0, 0, -kG));
  world.add_static_half_space(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  RigidBoxSpec s = box("D1", Eigen::Vector3d(0.15, 0.06, 0.06), 0.226, Eigen::Vector3d(0, 0, 0.03));
  s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()));
  world.add_box(s);
  DebrisRecorder rec(world, 30.0, 1000.0);  // solver-rate series thinned to 1 kHz
  rec.record();
  for (int k = 0; k < 2000; ++k) {
    world.step(1e-4);
    rec.record();
  }
  EXPECT_EQ(rec.solver_rate(0).size(), 201u);
  const auto& sf = rec.resampled(0).specific_force_body.back();
  EXPECT_NEAR(sf[0], 0.0, 1e-6);
  EXPECT_NEAR(sf[1], 0.0, 1e-6);
  EXPECT_NEAR(sf[2], kG, 1e-6);
}

}  // namespace
}  // namespace flume
