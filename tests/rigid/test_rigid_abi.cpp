// Compiled for the baseline x86-64 ISA while flume_rigid is built with -march=native (CMakeLists.txt): the public
// structs must have the same layout in both, as they will in a CUDA host file compiled without -march.
#include <gtest/gtest.h>

#include "solver/rigid/debris_recorder.h"
#include "solver/rigid/rigid_world.h"

namespace flume {
namespace {

TEST(Abi, StructsCrossTheLibraryBoundaryIntact) {
  RigidWorld world(ContactCoefficients{}, Eigen::Vector3d::Zero());
  RigidBoxSpec s;
  s.name = "D1";
  s.size = Eigen::Vector3d(0.15, 0.06, 0.06);
  s.mass = 0.226;
  s.position = Eigen::Vector3d(1, 2, 3);
  s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  s.velocity = Eigen::Vector3d(0.1, 0.2, 0.3);
  s.angular_velocity = Eigen::Vector3d(0.4, 0.5, 0.6);
  const int b = world.add_box(s);
  EXPECT_EQ(world.spec(b).name, "D1");
  const BodyState st = world.state(b);
  EXPECT_TRUE(st.position.isApprox(s.position, 1e-12));
  EXPECT_NEAR(std::abs(st.orientation.dot(s.orientation)), 1.0, 1e-12);
  EXPECT_TRUE(st.rotation.isApprox(s.orientation.toRotationMatrix(), 1e-12));
  EXPECT_TRUE(st.velocity.isApprox(s.velocity, 1e-12));
  EXPECT_TRUE(st.angular_velocity.isApprox(s.angular_velocity, 1e-12));
  DebrisRecorder rec(world);
  rec.record();
  world.step(0.05);
  rec.record();
  rec.finish();
  EXPECT_EQ(rec.resampled(0).size(), 2u);
  EXPECT_NEAR(rec.resampled(0).position[0][0], 1.0, 1e-12);
}

}  // namespace
}  // namespace flume
