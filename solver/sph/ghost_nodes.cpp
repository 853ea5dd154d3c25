#include "solver/sph/ghost_nodes.h"

#include <Eigen/Dense>
#include <cmath>

namespace flume::sph {

namespace {

struct Plane {
  Eigen::Vector3d n;  // unit
  double c;           // n . x = c on the plane
};

bool open_at(const Scene& s, const Vec3d& q, double tol) {
  for (int d = 0; d < s.dimension; ++d)
    if (q[d] < s.domain_lo[d] - tol || q[d] > s.domain_hi[d] + tol) return false;
  for (const auto& b : s.boundaries)
    if (b.condition != BoundaryCondition::kSymmetry && shape_distance(b.shape, q, s.dimension) < -tol)
      return false;
  return true;
}

// The planes of the domain's walls and of the solids' faces that pass within `reach` of p.
std::vector<Plane> planes_near(const Scene& s, const Vec3d& p, double reach) {
  const int D = s.dimension;
  std::vector<Plane> out;
  auto axis_plane = [&](int d, double at) {
    if (std::fabs(p[d] - at) > reach) return;
    Plane pl{Eigen::Vector3d::Zero(), at};
    pl.n[d] = 1;
    out.push_back(pl);
  };
  for (int d = 0; d < D; ++d) {
    axis_plane(d, s.domain_lo[d]);
    axis_plane(d, s.domain_hi[d]);
  }
  for (const auto& b : s.boundaries) {
    if (b.condition == BoundaryCondition::kSymmetry) continue;
    if (std::fabs(shape_distance(b.shape, p, D)) > reach) continue;
    if (b.shape.type == ShapeType::kHalfSpace) {
      Plane pl{Eigen::Vector3d::Zero(), 0};
      for (int d = 0; d < D; ++d) pl.n[d] = b.shape.normal[d];
      pl.n.normalize();
      for (int d = 0; d < D; ++d) pl.c += pl.n[d] * b.shape.point[d];
      out.push_back(pl);
    } else {
      for (int d = 0; d < D; ++d) {
        axis_plane(d, b.shape.lo[d]);
        axis_plane(d, b.shape.hi[d]);
      }
    }
  }
  return out;
}

// The point nearest p on the intersection of the planes in `pick` (false if they do not meet in a point, line
// or plane of the expected dimension: parallel planes).
bool project(const std::vector<Plane>& planes, const std::vector<int>& pick, const Eigen::Vector3d& p, int D,
             Eigen::Vector3d& q) {
  // At most three planes in three dimensions: fixed-capacity matrices, no allocation per candidate.
  using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
  using Vec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
  const int k = static_cast<int>(pick.size());
  Mat N(k, D);
  Vec r(k);
  for (int i = 0; i < k; ++i) {
    const Plane& pl = planes[pick[i]];
    for (int d = 0; d < D; ++d) N(i, d) = pl.n[d];
    r[i] = pl.n.head(D).dot(p.head(D)) - pl.c;
  }
  const Mat G = N * N.transpose();
  Eigen::FullPivLU<Mat> lu(G);
  if (lu.rank() < k) return false;
  q = p;
  q.head(D) -= N.transpose() * lu.solve(r);
  return true;
}

}  // namespace

std::vector<double> wall_ghost_vectors(const Scene& scene, const WallParticles& walls, double reach) {
  const int D = scene.dimension;
  const std::size_t n = walls.size();
  std::vector<double> ghost(3 * n, 0.0);
#pragma omp parallel for schedule(dynamic, 256)
  for (long k = 0; k < long(n); ++k) {
    const Vec3d p{walls.x[0][k], walls.x[1][k], walls.x[2][k]};
    const Eigen::Vector3d pe(p[0], p[1], p[2]);
    const std::vector<Plane> planes = planes_near(scene, p, reach);
    const int m = static_cast<int>(planes.size());
    const double tol = 1e-9 * std::max(reach, 1e-6);
    double best = reach * reach;
    Eigen::Vector3d nearest = pe;
    bool found = false;
    auto consider = [&](const std::vector<int>& pick) {
      Eigen::Vector3d q;
      if (!project(planes, pick, pe, D, q)) return;
      const double d2 = (q - pe).squaredNorm();
      if (d2 > best || (found && d2 == best)) return;
      if (!open_at(scene, Vec3d{q[0], q[1], q[2]}, tol)) return;
      best = d2;
      nearest = q;
      found = true;
    };
    // Faces first, then edges and corners: the nearest open point lies on one face, or where two or three
    // meet.
    for (int a = 0; a < m; ++a) consider({a});
    for (int a = 0; a < m && D >= 2; ++a)
      for (int b = a + 1; b < m; ++b) consider({a, b});
    for (int a = 0; a < m && D >= 3; ++a)
      for (int b = a + 1; b < m; ++b)
        for (int c = b + 1; c < m; ++c) consider({a, b, c});
    if (!found) continue;
    for (int d = 0; d < D; ++d) ghost[3 * k + d] = 2 * (nearest[d] - p[d]);
  }
  return ghost;
}

void box_ghost_vector(const double half[3], const double offset[3], int dim, double out[3]) {
  int axis = 0;
  double depth = 1e300;
  for (int a = 0; a < dim; ++a) {
    const double d = half[a] - std::fabs(offset[a]);
    if (d < depth) depth = d, axis = a;
  }
  for (int a = 0; a < 3; ++a) out[a] = 0;
  out[axis] = 2 * depth * (offset[axis] < 0 ? -1.0 : 1.0);
}

}  // namespace flume::sph
