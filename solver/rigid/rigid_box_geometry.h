// Geometry of one debris box as plain data, and the queries the MPM grid coupling needs (signed distance,
// outward normal, rigid surface velocity). No Eigen, no Bullet, no std containers: a RigidBoxView can be copied
// to the GPU as it is and the functions compile for host and device, so the CPU and CUDA grid updates share one
// definition (STYLE.md, AMReX *_K.H habit).
#pragma once
#include <cmath>

#if defined(__CUDACC__)
#define FLUME_RIGID_HD __host__ __device__
#else
#define FLUME_RIGID_HD
#endif

namespace flume {

// A box at one instant. `rotation` maps body axes to world axes (row-major: world = R * body), so its columns
// are the body axes in world coordinates. SI units; angular velocity in the world frame.
struct RigidBoxView {
  double centre[3];
  double rotation[9];
  double half_extent[3];
  double velocity[3];
  double angular_velocity[3];
};

// world -> body coordinates of the point p relative to the centre: R^T (p - c).
FLUME_RIGID_HD inline void box_to_body(const RigidBoxView& b, const double p[3], double local[3]) {
  const double d[3] = {p[0] - b.centre[0], p[1] - b.centre[1], p[2] - b.centre[2]};
  for (int j = 0; j < 3; ++j)
    local[j] = b.rotation[0 * 3 + j] * d[0] + b.rotation[1 * 3 + j] * d[1] + b.rotation[2 * 3 + j] * d[2];
}

// Exact Euclidean signed distance to the box surface: negative inside (the usual box SDF, e.g. Quilez,
// "distance functions": q = |x| - h; outside |max(q, 0)|, inside max(q_x, q_y, q_z)).
FLUME_RIGID_HD inline double box_signed_distance(const RigidBoxView& b, const double p[3]) {
  double local[3];
  box_to_body(b, p, local);
  double outside2 = 0.0, inside = -1e300;
  for (int j = 0; j < 3; ++j) {
    const double q = std::fabs(local[j]) - b.half_extent[j];
    if (q > 0.0) outside2 += q * q;
    inside = q > inside ? q : inside;
  }
  return outside2 > 0.0 ? std::sqrt(outside2) : inside;
}

// Unit outward normal: the gradient of box_signed_distance. Outside it points from the nearest surface point to
// p (so it is continuous round edges and corners); inside it is the normal of the nearest face (ties go to the
// lowest axis). At the centre of a cube every face is nearest and the first axis is returned.
FLUME_RIGID_HD inline void box_outward_normal(const RigidBoxView& b, const double p[3], double n[3]) {
  double local[3], g[3] = {0.0, 0.0, 0.0};
  box_to_body(b, p, local);
  double outside2 = 0.0;
  int face = 0;
  double inside = -1e300;
  for (int j = 0; j < 3; ++j) {
    const double s = local[j] < 0.0 ? -1.0 : 1.0;
    const double q = std::fabs(local[j]) - b.half_extent[j];
    if (q > 0.0) {
      g[j] = s * q;
      outside2 += q * q;
    }
    if (q > inside) {
      inside = q;
      face = j;
    }
  }
  if (outside2 > 0.0) {
    const double inv = 1.0 / std::sqrt(outside2);
    for (int j = 0; j < 3; ++j) g[j] *= inv;
  } else {
    g[face] = local[face] < 0.0 ? -1.0 : 1.0;
  }
  for (int i = 0; i < 3; ++i)
    n[i] = b.rotation[i * 3 + 0] * g[0] + b.rotation[i * 3 + 1] * g[1] + b.rotation[i * 3 + 2] * g[2];
}

// Velocity of the body's material point at p: v + omega x (p - c) (rigid-body kinematics).
FLUME_RIGID_HD inline void box_surface_velocity(const RigidBoxView& b, const double p[3], double v[3]) {
  const double r[3] = {p[0] - b.centre[0], p[1] - b.centre[1], p[2] - b.centre[2]};
  const double* w = b.angular_velocity;
  v[0] = b.velocity[0] + w[1] * r[2] - w[2] * r[1];
  v[1] = b.velocity[1] + w[2] * r[0] - w[0] * r[2];
  v[2] = b.velocity[2] + w[0] * r[1] - w[1] * r[0];
}

}  // namespace flume
