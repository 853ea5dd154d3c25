// The CPU (OpenMP) backend of the MLS-MPM solver on a block-sparse grid (docs/solver.md, "The CPU backend's
// parts"). Particles are structure-of-arrays, kept sorted by grid block (BlockGrid, solver/mpm/cpu_blocks.h).
//
// Race-free scatter by design. Each particle block scatters (P2G) into its own tile of kTile^D nodes, a
// private buffer no other thread touches; each grid block then gathers the overlapping parts of the tiles of
// its 3^D neighbouring particle blocks, in a fixed order (solver/mpm/tiles.h). No atomics, and the result
// does not depend on the number of threads.
//
// This header declares the class; its members are defined by job in solver/mpm/cpu_*.cpp: cpu_solver.cpp
// (set-up, the step, inflow, the factory), cpu_p2g.cpp, cpu_grid_update.cpp (node update, symmetry fold),
// cpu_g2p.cpp, cpu_boundaries.cpp (walls, symmetry mirror), cpu_checkpoint.cpp (checkpoint, energy audit,
// diagnostics). Parts with state of their own: BlockGrid (sort and block lists), GhostReflection
// (cpu_ghosts.h), CpuDebris (cpu_debris.h), SymmetryZone (symmetry_zone.h), ThreadShares (thread_shares.h).
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "solver/checkpoint.h"
#include "solver/inflow.h"
#include "solver/instruments.h"
#include "solver/mpm/constants.h"
#include "solver/mpm/cpu_blocks.h"
#include "solver/mpm/cpu_debris.h"
#include "solver/mpm/cpu_ghosts.h"
#include "solver/mpm/cpu_variants.h"
#include "solver/mpm/node_k.h"
#include "solver/mpm/probe_k.h"
#include "solver/mpm/run_state.h"
#include "solver/mpm/symmetry_zone.h"
#include "solver/mpm/thread_shares.h"
#include "solver/mpm/tiles.h"
#include "solver/mpm_kernels.h"
#include "solver/simulation.h"

namespace flume::mpm {

template <int D, typename T, bool Flip>
class MpmSolver final : public Simulation, private SceneConstants<D, T> {
  static constexpr int kNodes = Pow<D>::of(kBlock);
  static constexpr int kTileNodes = Pow<D>::of(kTile);
  static constexpr int kNbr = Pow<D>::of(3);
  // Mass, momentum (D), mass-weighted strain J - 1, particle volume; in a FLIP solver (the factory's choice
  // where solver.flip > 0) also the momentum of the transfer alone (D, mpm::p2g_transfer_momentum), the grid's
  // old velocity, which takes a 3D node to 9 channels and so to 16 lanes. An APIC run does none of that work.
  static constexpr int kFlipChannels = Flip ? D : 0;
  static constexpr int kChannels = D + 3 + kFlipChannels;
  // Tiles and the grid gather hold a node's channels side by side, padded to one SIMD vector (Eigen packet):
  // a particle's contribution to a node is then one vector multiply-add, not kChannels scalar ones. G2P's
  // tile holds per node the velocity, the free-node weight 1 (0 on a wall node) and the strain and fill times
  // it (and FLIP's old velocity), so one vector multiply-add per node gathers all of them.
  static constexpr int kLanes = kChannels <= 8 ? 8 : 16;
  static constexpr int kBatch = 32;  // particles per pass of the P2G and G2P batch loops
  static_assert(kChannels <= kLanes, "channels must fit the lanes");
  using Lane = Eigen::Array<T, kLanes, 1>;
  using LaneMap = Eigen::Map<Lane>;
  using ConstLaneMap = Eigen::Map<const Lane>;
  using TileBox = mpm::TileBox<D>;
  using K = SceneConstants<D, T>;  // the scene's constants (constants.h)
  using K::dx_, K::inv_dx_, K::grid_lo_, K::gravity_, K::mu_, K::psi_, K::flip_, K::law_, K::law_d_,
      K::strain_slope_, K::c_;

 public:
  MpmSolver(const Scene& scene, const SimulationOptions& options);  // cpu_solver.cpp

  // --- Simulation (cpu_solver.cpp unless said) ---
  RunStatus step() override;
  double time() const override { return run_.time; }
  double last_dt() const override { return run_.dt; }
  long steps() const override { return run_.steps; }
  size_t particle_count() const override { return n_; }
  double total_mass() const override { return run_.mass; }
  const Record& record() const override { return instruments_.record(); }
  const std::string& message() const override { return run_.message; }
  void particle_positions(std::vector<double>& xyz) const override;   // cpu_checkpoint.cpp
  void particle_velocities(std::vector<double>& vel) const override;  // cpu_checkpoint.cpp
  void particle_pressures(std::vector<double>& p) const override;     // cpu_checkpoint.cpp
  size_t grid_bytes() const override;
  size_t active_blocks() const override { return blocks_.gkeys.size(); }
  size_t particle_bytes() const override { return n_ * sizeof(T) * (2 * D + D * D + 2); }
  std::vector<std::pair<std::string, double>> stage_seconds() const override;
  double bytes_per_step() const override;
  void momentum(double linear[3], double angular[3]) const override;  // cpu_checkpoint.cpp
  void set_rigid_velocity(const double v0[3], const double omega[3],
                          const double centre[3]) override;  // ditto
  const DebrisCoupling* debris() const override { return debris_ ? &debris_->bodies() : nullptr; }
  DebrisCoupling* debris() override { return debris_ ? &debris_->bodies() : nullptr; }
  void checkpoint(StateArchive& ar) override;  // cpu_checkpoint.cpp

  // --- read access for the instruments (solver/instruments.h) ---
  int dim() const { return D; }
  size_t n() const { return n_; }
  T x(int d, size_t i) const { return x_[d][i]; }
  T v(int d, size_t i) const { return v_[d][i]; }
  T volume(size_t i) const { return vol_[i]; }  // reference volume: the particle's mass over rho
  double max_speed() const { return run_.max_speed; }
  const Scene& scene() const { return scene_; }
  // The pressure probes read the walls' push at the nodes (mpm::add_probe_push): per probe, the last step's
  // sum of weight times push along its normal (N s).
  static constexpr bool kProbesReadWallPush = true;
  const std::vector<double>& probe_push() const { return probe_push_; }

  // --- the energy audit (cpu_checkpoint.cpp) ---
  Energy energy() const;
  const Energy& last_energy() const { return run_.last_energy; }

 private:
  struct ProbeHit {  // a node's push within a pressure probe's reach (grid_update)
    size_t idx;
    double x[D], push[D];
  };
  // --- set-up (cpu_solver.cpp, cpu_boundaries.cpp) ---
  void seed_particles();
  void setup_boundaries();
  ParticleArrays<D, T> particle_arrays();
  // --- the stages ---
  void sort_particles();  // BlockGrid::sort, then fit_to_blocks
  void fit_to_blocks();   // the node arrays, tiles and symmetry zone to the block lists
  TileBox tile_box(long p, const T* lo_grid, T inv_dx) const;  // cpu_p2g.cpp
  void p2g(T dt);                                              // cpu_p2g.cpp
  void grid_update(T dt);                                      // cpu_grid_update.cpp
  void update_node(const Lane& acc, long g, size_t idx, const int* node, bool near_debris, double load_weight,
                   T dt, T inv_cell_volume, double* my_impulse, std::vector<ProbeHit>* my_probe_hits,
                   std::vector<CouplingNode>* my_coupling,
                   std::vector<Ghost<D, T>>* my_ghosts);  // cpu_grid_update.cpp
  void mirror_beyond_symmetry();                          // cpu_boundaries.cpp
  void g2p(T dt);                                         // cpu_g2p.cpp
  void apply_inflow(double t0, double t1);                // cpu_solver.cpp
  void fail(const std::string& what);

  // The scene and the constants not in SceneConstants.
  Scene scene_;
  InstrumentSet<MpmSolver> instruments_;
  T fill_tolerance_ = 0;  // mpm::fill_correction
  double spacing_ = 0, rho_ = 0;

  // The particles (structure of arrays, in block order).
  size_t n_ = 0;
  std::vector<T> x_[D], v_[D], C_[D * D], e_;  // e: volumetric strain J - 1
  std::vector<T> vol_;   // reference volume (solver/seeding.h): the particle's mass is rho vol
  std::vector<T> held_;  // 1 for water the reservoir's vacuum holds (empty when nothing is held)
  std::vector<T> tag_;   // the inflow's buffer particles (1) and free water (0); empty without an inflow

  // The block grid, the tiles and the nodes.
  BlockGrid<D, T> blocks_;
  bool needs_sort_ = true;
  std::vector<TileBox> tile_box_;  // per particle block: read by the grid gather and by G2P
  bool boxes_current_ = false;     // tile_box_ fits the present positions (G2P leaves them for P2G)
  std::vector<T> tiles_;           // per particle block, kLanes x kTileNodes: P2G's private scatter
  GridNodes<D, T> grid_;
  ThreadShares shares_;  // each thread's particle and grid blocks, the same in every stage (thread_shares.h)

  // Boundaries: walls, the domain box, ghosts, the symmetry plane, loads.
  std::vector<Wall<D, T>> walls_;
  Container<D, T> container_;         // the domain box
  double subcell_rate0_ = 0;          // mpm::subcell_drag's rate
  std::vector<double> load_impulse_;  // D per wall: this step's impulse on the water (the load cells' input)
  std::vector<double> probe_geometry_;  // the pressure probes' points and normals (mpm::probe_geometry)
  ProbeFaces probe_faces_;              // a view of them
  std::vector<double> probe_push_;      // per probe: this step's push (mpm::add_probe_push)
  // The pushes within a probe's reach, per thread, summed afterwards in node order: the probes' readings then
  // do not depend on the thread count (as the particles' sums do not).
  std::vector<std::vector<ProbeHit>> probe_hits_;
  bool within_probe_reach(const double* x) const {
    double image[D];
    for (int d = 0; d < D; ++d) image[d] = x[d];
    if (has_sym_) image[sym_.axis] = 2 * sym_.at - x[sym_.axis];
    for (int q = 0; q < probe_faces_.count; ++q)
      if (probe_node_weight<D>(probe_faces_, q, x) > 0 ||
          (has_sym_ && probe_node_weight<D>(probe_faces_, q, image) > 0))
        return true;
    return false;
  }
  GhostReflection<D, T> ghosts_;
  bool has_sym_ = false;
  SymmetryPlane sym_;
  SymmetryZone<D> zone_;       // the nodes near the symmetry plane, stored raw and updated after the fold
  std::vector<Lane> sym_acc_;  // per zone entry: this step's raw lanes

  // Debris and inflow (absent unless the scene has them).
  std::unique_ptr<CpuDebris<D, T>> debris_;
  std::unique_ptr<InflowBoundary<D, T>> inflow_;

  // The clock, the audit and the run's state.
  enum Stage { kStageSort, kStageP2g, kStageGrid, kStageG2p, kStageOther, kStages };
  double stage_s_[kStages] = {};  // wall seconds per stage of the steps so far (stage_seconds)
  RunState run_;                  // the clock, the audit's budget, the status (run_state.h)
};

}  // namespace flume::mpm
