// Two-way coupling of rigid debris (RigidWorld, Bullet contact) with the MPM water, through the grid.
//
// Each step, after the grid velocities are updated and the scene's walls applied, every grid node with water
// mass in or within one cell of a debris box (signed distance <= dx; why one cell: solver/mpm/cpu_debris.h,
// CpuDebris::kBand) is a moving-wall node of that box: like a wall node,
// its velocity may not approach the box's surface (the `separate` condition of eq. 2, no friction: the water
// may leave the box, slide along it, not enter it). The impulse that removes the approach is what the water
// and the box exchange.
//
// The exchange is solved implicitly for the box's velocity. With U = (v, omega) the box's velocity, M its
// 6x6 mass matrix (m I, world inertia) and G_i = (n_i, r_i x n_i) the Jacobian of node i's normal velocity,
// the box after the step and its active nodes satisfy
//     (M + sum_i m_i G_i G_i^T) U' = M U + F_gravity dt + sum_i m_i G_i (n_i . v_i),
// i.e. a perfectly inelastic normal collision between the box and the water mass on its nodes, momentum
// conserving by construction. An explicit exchange (the water's impulse computed against the old U and
// applied afterwards) overshoots when the node water mass exceeds the box's mass, which it does for a 419
// kg/m^3 container in water (the added-mass instability of partitioned coupling); the implicit one does not.
// The active set (nodes approaching the box) is iterated to a fixed point (a few sweeps).
//
// The water's load F = M (U' - U) / dt - F_gravity (force and torque about the centre) is then handed to
// RigidWorld, which adds gravity and contact and steps the boxes by dt; the nodes take the box's normal
// velocity at U'. Buoyancy and drag come out of the water's pressure on the nodes, not out of a formula.
//
// Grid nodes alone cannot keep a moving box's face from overtaking the water particles just ahead of it (a
// particle's velocity interpolates constrained and free nodes, so it lags the face): after G2P, a particle
// inside a box is moved back to its surface and its approach velocity removed, as a wall would; the momentum
// it loses is given to the box with the next exchange, so the pair still conserves momentum.
//
// The water film under a resting box. A box standing on the floor (or on another box) is wetted underneath in a
// real flume: the water seeps into the gap, which is far below a cell (the Waseda containers stand 0.5 mm off
// the apron), so no particle reaches it and the grid alone held a buoyant box on the floor whatever the depth
// (measured: a 419 kg/m^3 container in 4.5 cm of still water, draft 2.5 cm, never left the floor at dx 0.03,
// 0.02 or 0.01 m). So the box's lowest face (its outward normal within 45 degrees of gravity) carries the
// film's pressure where a solid lies less than a cell beneath it: the face is cut into patches of at most half
// a cell, and a patch whose gap g to the solid below (found to 1/256 of a cell) is under dx takes the pressure
// p_f (1 - g / dx); at g >= dx the grid resolves the water there and the film is gone. p_f is the water's
// pressure round the face's rim at the face's level (the node layer there, each node's pressure carried to the
// face hydrostatically), averaged over the rim in bins of at least 1.5 cells (each holds a node column whatever
// the alignment), a dry bin counting 0 and a bin inside a solid not at all: in still water it is rho g times
// the depth, so the box floats at Archimedes' draft; a box on a dry floor with water on one side feels part of
// it. The film pushes the face away from the solid and the solid back: a supporting box takes the reaction at
// the patch, a static solid needs none. It is a sub-grid closure of the gap, not a formula for buoyancy: the
// pressure is the water's own, read off the nodes.
//
// Deterministic: nodes are summed in grid order whatever the thread count. The per-node and per-particle
// bodies both backends run are in solver/mpm/debris_k.h; this class is the host side.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "solver/mpm/debris_k.h"
#include "solver/rigid/debris_recorder.h"
#include "solver/rigid/rigid_world.h"
#include "solver/scene.h"

namespace flume {

class DebrisCoupling {
 public:
  explicit DebrisCoupling(const Scene& scene);

  int body_count() const { return world_.body_count(); }
  const RigidWorld& world() const { return world_; }
  const DebrisRecorder& recorder() const { return *recorder_; }
  const std::vector<RigidBoxView>& views() const { return world_.box_views(); }
  double bounding_radius(int body) const { return radius_[body]; }
  const std::vector<double>& bounding_radii() const { return radius_; }

  // The box holding point x, the deepest when several do (signed distance <= tol), or -1. Writes its outward
  // normal at x.
  int locate(const double x[3], double tol, double n[3]) const;

  // Solves the exchange for `nodes` (sorted by id), sets their projected velocities, applies the water's loads
  // and steps the boxes by dt; records the trajectories.
  void exchange(std::vector<CouplingNode>& nodes, double dt);

  // For a method that sums the water's loads itself (SPH, over each box's boundary particles): load[b] is the
  // water's force (N) and torque about the centre (N m) on box b over the next dt, world frame. Applies them,
  // steps the boxes by dt and records the trajectories.
  void step_with_loads(const std::vector<Eigen::Matrix<double, 6, 1>>& load, double dt);

  // The film under each resting box (the header) from water points round the boxes, each with its body,
  // position, mass and pressure: for SPH, the particles within a cell of a box. Returns each body's film load
  // (force, torque about the centre; a supporting box takes the reaction) and records the film's force.
  std::vector<Eigen::Matrix<double, 6, 1>> film(const std::vector<CouplingNode>& points);

  // Water particles found inside a box after G2P are put back on its surface, their velocity's approach
  // removed (debris_coupling.cpp); the momentum they lose goes to the box in the next exchange. `impulse` is
  // the box's share (N s, world frame) and `moment` its moment about the origin (sum of x cross impulse).
  void add_particle_impulse(int body, const double impulse[3], const double moment[3]);

  // Kinetic and potential energy of the boxes (J): for the solver's energy audit.
  double energy() const;
  // The water's force on each body over the last step (N, world frame): for instruments and tests.
  const std::vector<Eigen::Vector3d>& water_force() const { return water_force_; }
  // The part of it the film under the box gave (N, world frame; see the header).
  const std::vector<Eigen::Vector3d>& film_force() const { return film_force_; }

  void finish() { recorder_->finish(); }

  // The boxes, their recorded trajectories and the loads pending for the next exchange (solver/checkpoint.h).
  void checkpoint(StateArchive& ar);

 private:
  RigidWorld world_;
  std::unique_ptr<DebrisRecorder> recorder_;
  std::vector<double> radius_;
  // The film's loads (force, torque about the centre) on every body, from the nodes of each (indices into nodes).
  void film_loads(const std::vector<CouplingNode>& nodes, const std::vector<std::vector<size_t>>& of,
                  std::vector<Eigen::Matrix<double, 6, 1>>& load);
  // The indices of the points (nodes or particles) of each body, in their given order.
  std::vector<std::vector<size_t>> points_of(const std::vector<CouplingNode>& points) const;
  // film_loads, its forces recorded in film_force_.
  std::vector<Eigen::Matrix<double, 6, 1>> recorded_film(const std::vector<CouplingNode>& points,
                                                         const std::vector<std::vector<size_t>>& of);
  bool in_static_solid(const Eigen::Vector3d& x) const;
  int box_at(const Eigen::Vector3d& x, int skip) const;  // the debris box holding x (other than `skip`), or -1

  std::vector<Eigen::Vector3d> water_force_, film_force_;
  std::vector<Shape> solids_;                  // the scene's static solids, for the film's gap
  Eigen::Vector3d domain_lo_, domain_hi_;      // beyond these the domain's walls are solid
  double dx_ = 0, rho_water_ = 0;
  std::vector<Eigen::Matrix<double, 6, 1>> pending_;  // particle impulses for the next exchange (force, torque)
  Eigen::Vector3d gravity_;
};

// The seeding's test for the water a box displaces (solver/seeding.h): a point (D coordinates) inside a box is
// not seeded. Empty without debris.
template <int D>
std::function<bool(const double*)> displaced_by(const DebrisCoupling* debris) {
  if (!debris) return {};
  return [debris](const double* p) {
    double x3[3] = {0, 0, 0}, n[3];
    for (int d = 0; d < D; ++d) x3[d] = p[d];
    return debris->locate(x3, 0.0, n) >= 0;
  };
}

}  // namespace flume
