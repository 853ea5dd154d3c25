// The shared physics functions (solver/mpm_kernels.h) against independent references.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "solver/mpm/cpu_ghosts.h"
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

// The free-slip mirror's exchange between a ghost node and its mirror node. Tangential axes: momentum conserved,
// the velocities equal afterwards, kinetic energy never raised. Normal axis: the ghost keeps what the wall gave
// it, and the mirror takes the ghost's mass and its reflected pre-wall momentum, the image's push.
TEST(GhostMirror, ExchangeConservesTangentialMomentumAndCannotAddEnergy) {
  using flume::mpm::ghost_exchange;
  const double mg = 0.03, mm = 1.2;
  const double vg[3] = {0.9, -0.4, 0.0}, vpre[3] = {0.9, -0.4, -0.2}, vm[3] = {0.2, 0.5, 0.3};
  double dvg[3], dvm[3];
  ghost_exchange<3>(vg, vpre, mg, vm, mm, 1u << 2, 7u, dvg, dvm);  // normal along z
  for (int a = 0; a < 2; ++a) EXPECT_NEAR(mg * dvg[a] + mm * dvm[a], 0.0, 1e-16) << a;
  for (int a = 0; a < 2; ++a) EXPECT_NEAR(vg[a] + dvg[a], vm[a] + dvm[a], 1e-15) << a;
  double before = 0, after = 0;
  for (int a = 0; a < 2; ++a) {
    before += 0.5 * (mg * vg[a] * vg[a] + mm * vm[a] * vm[a]);
    after += 0.5 * (mg * (vg[a] + dvg[a]) * (vg[a] + dvg[a]) + mm * (vm[a] + dvm[a]) * (vm[a] + dvm[a]));
  }
  EXPECT_LT(after, before);
  EXPECT_EQ(dvg[2], 0.0) << "the ghost's normal velocity is the wall condition's";
  EXPECT_EQ(dvm[2], 0.0) << "a mirror moving away from the wall is not pushed";
  // The mirror image of the mirror: nothing to exchange.
  const double image[3] = {vm[0], vm[1], -vm[2]};
  ghost_exchange<3>(vm, image, mg, vm, mm, 1u << 2, 7u, dvg, dvm);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(dvg[a], 0.0);
    EXPECT_NEAR(dvm[a], 0.0, 1e-16);
  }
}

// Water at rest against a wall: the first fluid node off it is pushed towards the wall by the pressure of the
// particles on its fluid side (its stencil's wall side holds none), and the ghost node is pushed into the wall by
// the same particles. By the mirror symmetry the two momenta are equal and opposite in the mirror's frame, so the
// image's push stops the mirror node: no crowding against the wall.
TEST(GhostMirror, ImagePushBalancesTheOneSidedPressureNextToAWall) {
  const double mg = 0.2, mm = 1.0;
  const double push = 1e-3;                      // the one-sided pressure's momentum on each, kg m/s
  const double vm[2] = {-push / mm, 0.0};        // the mirror, pushed towards the wall at x < 0 (normal along x)
  const double vpre[2] = {-push / mg, 0.0};      // the ghost before the wall condition: pushed into the wall
  const double vg[2] = {0.0, 0.0};               // after it
  double dvg[2], dvm[2];
  flume::mpm::ghost_exchange<2>(vg, vpre, mg, vm, mm, 1u << 0, 3u, dvg, dvm);
  EXPECT_NEAR(vm[0] + dvm[0], 0.0, 1e-18);
  EXPECT_EQ(dvg[0], 0.0);
  // A weaker push only slows it (the pooled velocity); a stronger one stops it and no more: a contact force does
  // no positive work.
  const double weak[2] = {-0.5 * push / mg, 0.0}, strong[2] = {-3 * push / mg, 0.0};
  flume::mpm::ghost_exchange<2>(vg, weak, mg, vm, mm, 1u << 0, 3u, dvg, dvm);
  EXPECT_NEAR(vm[0] + dvm[0], (mm * vm[0] - mg * weak[0]) / (mm + mg), 1e-18);
  EXPECT_LT(vm[0] + dvm[0], 0.0);
  flume::mpm::ghost_exchange<2>(vg, strong, mg, vm, mm, 1u << 0, 3u, dvg, dvm);
  EXPECT_EQ(vm[0] + dvm[0], 0.0);
  // The same wall seen from the other side (fluid towards lower indices): the signs flip with it.
  const double vm_r[2] = {push / mm, 0.0}, vpre_r[2] = {push / mg, 0.0};
  const unsigned axes_r = (1u << 0) | (1u << (0 + flume::mpm::kGhostSignShift));
  flume::mpm::ghost_exchange<2>(vg, vpre_r, mg, vm_r, mm, axes_r, 3u, dvg, dvm);
  EXPECT_NEAR(vm_r[0] + dvm[0], 0.0, 1e-18);
}

// Next to a concave edge three ghosts reflect onto one mirror node (one beyond each wall, one beyond both),
// here with as much water as the mirror, as where the water has run into the corner. They and the mirror are
// one perfectly inelastic collision: along z, tangential to every wall, momentum is conserved, all four leave
// with one velocity and the impulses do no work on it; along x the two images of the wall at x < 0 pooled
// stop the mirror at most, and the wall takes that push once. Pairwise exchanges summed at the mirror did
// work (2/3 J here), left the mirror at rest and the ghosts moving, and reversed the mirror off the wall.
TEST(GhostMirror, GhostsSharingAMirrorExchangeAsOneCollision) {
  using flume::mpm::Ghost;
  using Grid = flume::mpm::GridNodes<3, double>;
  const std::vector<uint64_t> gkeys = {0};  // one block, nodes (0..3)^3
  const auto index = [](int i, int j, int k) { return static_cast<size_t>((i * 4 + j) * 4 + k); };
  Grid grid;
  grid.resize(64);
  const size_t mirror = index(1, 1, 1);
  grid.m[mirror] = 1.0;
  const double vm[3] = {-0.2, 0.0, 1.0};  // towards the wall at x < 0, along the edge
  for (int d = 0; d < 3; ++d) grid.v[d][mirror] = vm[d];
  struct Spec {
    int i, j;
    unsigned axes;
  };
  std::vector<Ghost<3, double>> ghosts;
  for (const Spec& s : {Spec{0, 0, 3u}, Spec{0, 1, 1u}, Spec{1, 0, 2u}}) {  // in node order
    Ghost<3, double> g;
    g.idx = index(s.i, s.j, 1);
    g.axes = s.axes;
    g.offset[0] = g.offset[1] = g.offset[2] = 1;  // the mirror node
    g.vpre[0] = g.vpre[1] = -1.0;                 // pushed into the walls by the water
    g.wall = 0;
    grid.m[g.idx] = 0.5;
    grid.wall[g.idx] = 1;
    ghosts.push_back(g);
  }
  flume::mpm::GhostReflection<3, double> reflection;
  reflection.set_push_axes(3u);
  reflection.begin(1);
  *reflection.thread_list(0) = ghosts;
  std::vector<double> load(3, 0.0);
  std::vector<double> no_probes;
  reflection.reflect(grid, gkeys, load, flume::mpm::ProbeFaces{}, no_probes);

  double momentum = 0, work = 0;
  for (size_t i : {mirror, ghosts[0].idx, ghosts[1].idx, ghosts[2].idx}) {
    const double before = i == mirror ? vm[2] : 0.0;
    momentum += grid.m[i] * grid.v[2][i];
    work += grid.m[i] * (grid.v[2][i] - before) * grid.v[2][i];
    EXPECT_NEAR(grid.v[2][i], grid.v[2][mirror], 1e-15) << "node " << i;
  }
  EXPECT_NEAR(momentum, grid.m[mirror] * vm[2], 1e-15);
  EXPECT_NEAR(work, 0.0, 1e-15);
  EXPECT_LE(grid.v[0][mirror], 0.0) << "the images stop the mirror at most";
  EXPECT_GE(grid.v[0][mirror], vm[0]);
  EXPECT_NEAR(std::fabs(load[0]), grid.m[mirror] * (grid.v[0][mirror] - vm[0]), 1e-15);
}

// Walls push with their ghosts' image across gravity only: a 2D scene's side walls (x), a 3D scene's side walls and
// symmetry planes (x, y), never a floor.
TEST(GhostMirror, ImagePushesAcrossGravityOnly) {
  const double g2[2] = {0.0, -9.80665}, g3[3] = {0.0, 0.0, -9.80665};
  EXPECT_EQ(flume::mpm::image_push_axes<2>(g2), 1u);
  EXPECT_EQ(flume::mpm::image_push_axes<3>(g3), 3u);
}

// The mirror node of a ghost is the node nearest its reflection, also when the wall lies between grid lines.
TEST(GhostMirror, MirrorNodeIsNearestTheReflection) {
  using flume::mpm::ghost_half_space;
  const double n[2] = {-1.0, 0.0};  // a solid x > 4.45 (the quay's upstream face), fluid at x < 4.45
  const double point[2] = {4.45, 0.0};
  for (const auto& [x, expect] :
       std::vector<std::pair<double, int>>{{4.46, -1}, {4.48, -3}, {4.455, -1}, {4.4525, 0}}) {
    int offset[2] = {0, 0};
    unsigned axes = 0;
    bool ambiguous = false;
    const double xn[2] = {x, 0.1};
    ghost_half_space<2>(xn, point, n, 0.02, offset, axes, ambiguous);
    // 4.455 is a quarter cell in: its reflection is as near the next node as itself, so it is a
    // ghost; 4.4525, an eighth of a cell in, is its own image (held, not a ghost).
    EXPECT_EQ(offset[0], expect) << "node at x = " << x;
    EXPECT_FALSE(ambiguous);
    // A ghost's axes say the fluid lies towards lower x.
    if (expect != 0) {
      EXPECT_EQ(axes, (1u << 0) | (1u << flume::mpm::kGhostSignShift)) << "node at x = " << x;
    }
  }
}

// The quay's crest at dx = 0.02 m: a box x > 4.45, z < 0.255 (both faces between grid lines). Water beyond a face
// reaches a node inside only within the stencil's 1.5 cells, so a node 1.5 cells behind the front face and under
// the top is held by the top alone (flow along the crest is tangential there), while one half a cell behind the
// front face is held by both. Before, every face within 2 cells held a node, and the sheet crossing the crest
// lost its streamwise velocity on the first two nodes (docs/validation.md, section 1).
TEST(BoxFaces, ANodeIsHeldOnlyByFacesWhoseWaterReachesIt) {
  using flume::mpm::wall_faces;
  const double lo[2] = {4.45, -1.0}, hi[2] = {20.0, 0.255};
  double n[4][2];
  const double behind[2] = {4.48, 0.24};  // 1.5 cells in from the front face, 0.75 under the top
  ASSERT_EQ(wall_faces<2>(behind, true, lo, hi, 0.02, n), 1);
  EXPECT_EQ(n[0][0], 0.0);
  EXPECT_EQ(n[0][1], 1.0) << "held by the top only";
  const double edge[2] = {4.46, 0.24};  // half a cell in from the front face
  EXPECT_EQ(wall_faces<2>(edge, true, lo, hi, 0.02, n), 2) << "held by the front face and the top";
  // A thin panel (the 0.04 m gate at dx 0.02 m): both faces hold its inner nodes.
  const double plo[2] = {1.0, 0.1}, phi[2] = {1.04, 1.0}, inside[2] = {1.02, 0.5};
  EXPECT_EQ(wall_faces<2>(inside, true, plo, phi, 0.02, n), 2);
}

// The velocity a box wall leaves a node with, as the grid update applies it (mpm::apply_box_wall).
std::pair<double, double> held_by_box(const double* lo, const double* hi, double x, double z, double u, double w) {
  const double xn[2] = {x, z};
  double n[4][2];
  const int faces = flume::mpm::wall_faces<2>(xn, true, lo, hi, 0.02, n);
  double v[2] = {u, w};
  const double vb[2] = {0, 0};
  if (faces) flume::mpm::apply_box_wall<2>(v, xn, lo, hi, 0.02, n, faces, vb, flume::mpm::Bc::kSlip, 0.0, 5.0e2, 1e-4);
  return {v[0], v[1]};
}

// The basin's gate at dx = 0.02 m: a slip panel 0.04 m (two cells) thick whose lower edge, 0.10 m up, lies on a
// grid line. Water flowing under it passes its lip row and its corners: a node on the panel's lower face is a
// point of a plane wall, free along it, and one on its lip corner stops only a velocity entering the panel.
// wall_faces' hold alone (by both faces of the thin panel and by the lower one) made them stagnation points
// and choked the flow under the gate by a fifth (docs/validation.md, section 1). Inside the panel, a cell or
// more from its lower face, both faces still hold a node.
TEST(BoxSurface, FlowUnderTheGatesLipPasses) {
  const double lo[2] = {0.50, 0.10}, hi[2] = {0.54, 1.0};
  const auto corner = held_by_box(lo, hi, 0.50, 0.10, 1.0, -0.3);  // under the lip, going down and on
  EXPECT_DOUBLE_EQ(corner.first, 1.0);
  EXPECT_DOUBLE_EQ(corner.second, -0.3);
  // Into the corner, through both faces: held whole. The nearest admissible velocity (1, 0) would turn still
  // water's push into the corner into a current along the lip.
  const auto into = held_by_box(lo, hi, 0.50, 0.10, 1.0, 0.3);
  EXPECT_NEAR(into.first, 0.0, 1e-12);
  EXPECT_NEAR(into.second, 0.0, 1e-12);
  const auto round = held_by_box(lo, hi, 0.54, 0.10, 0.2, 0.3);  // the downstream corner, rising round it
  EXPECT_DOUBLE_EQ(round.first, 0.2);
  EXPECT_DOUBLE_EQ(round.second, 0.3);
  const auto lip = held_by_box(lo, hi, 0.52, 0.10, 1.0, 0.0);  // the panel's lower face, mid-thickness
  EXPECT_DOUBLE_EQ(lip.first, 1.0);
  const auto inner = held_by_box(lo, hi, 0.52, 0.14, 1.0, 0.2);  // two cells up inside the panel
  EXPECT_NEAR(inner.first, 0.0, 1e-12);
}

// The gate's height is calibrated: as its lower face moves up through the grid the velocity a node keeps changes
// smoothly, where the node comes onto the face and where the face is a cell away (each face's share falls
// linearly to zero a cell in from it, mpm::surface_faces).
TEST(BoxSurface, ANodesVelocityIsContinuousAsTheFaceMoves) {
  const double hi[2] = {0.54, 1.0}, eps = 1e-7;
  for (double x : {0.50, 0.52, 0.54})
    for (double cells : {0.0, 1.0}) {
      const double below[2] = {0.50, 0.10 - cells * 0.02 - eps}, above[2] = {0.50, 0.10 - cells * 0.02 + eps};
      const auto a = held_by_box(below, hi, x, 0.10, 1.0, 0.3), b = held_by_box(above, hi, x, 0.10, 1.0, 0.3);
      if (cells == 0) continue;  // at the face itself the node leaves the box (the subcell cover takes over)
      EXPECT_NEAR(a.first, b.first, 1e-4) << "x " << x << ", face " << cells << " cells below";
      EXPECT_NEAR(a.second, b.second, 1e-4) << "x " << x << ", face " << cells << " cells below";
    }
  const double on[2] = {0.50, 0.10}, just_under[2] = {0.50, 0.10 - eps};
  for (double x : {0.50, 0.52, 0.54}) {
    const auto a = held_by_box(on, hi, x, 0.10, 1.0, 0.3), b = held_by_box(just_under, hi, x, 0.10, 1.0, 0.3);
    EXPECT_NEAR(a.first, b.first, 1e-4) << "x " << x << ", on the face";
    EXPECT_NEAR(a.second, b.second, 1e-4) << "x " << x << ", on the face";
  }
}

// Near a convex edge a ghost node is reached by water on two sides and has no image (the diagonal reflection is a
// concave corner's): it keeps its own velocity. Next to one face only, its mirror is across that face.
TEST(GhostMirror, ConvexEdgeHasNoImage) {
  using flume::mpm::ghost_box;
  const double lo[2] = {4.45, -1.0}, hi[2] = {20.0, 0.255};
  int offset[2] = {0, 0};
  unsigned axes = 0;
  bool ambiguous = false;
  const double corner[2] = {4.46, 0.23};  // 0.5 cells behind the front face, 1.25 under the top
  ghost_box<2>(corner, lo, hi, 0.02, offset, axes, ambiguous);
  EXPECT_TRUE(ambiguous) << "no diagonal mirror at a convex edge";
  EXPECT_EQ(axes, 0u);
  offset[0] = offset[1] = 0;
  axes = 0;
  ambiguous = false;
  const double under_top[2] = {4.48, 0.24};  // 1.5 cells behind the front face: the top's ghost only
  ghost_box<2>(under_top, lo, hi, 0.02, offset, axes, ambiguous);
  EXPECT_FALSE(ambiguous);
  EXPECT_EQ(axes, 1u << 1);
  EXPECT_EQ(offset[0], 0);
  EXPECT_EQ(offset[1], 2) << "the node nearest the reflection across the top, 0.27 m: 0.28 m";
}

}  // namespace
