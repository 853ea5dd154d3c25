// MpmSolver (solver/mpm/cpu_solver.h): set-up, the step and its stage clock, the block grid's sizing, the
// inflow, the memory figures; and make_cpu_simulation, the CPU backend's factory.
#include "solver/mpm/cpu_solver.h"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "common/errors.h"
#include "solver/cpu_kernels.h"
#include "solver/mpm/audit.h"
#include "solver/seeding.h"

namespace flume {
namespace mpm {

template <int D, typename T, bool Flip>
MpmSolver<D, T, Flip>::MpmSolver(const Scene& scene, const SimulationOptions& options)
    : SceneConstants<D, T>(scene), scene_(scene), instruments_(scene_) {
  if (options.threads > 0) omp_set_num_threads(options.threads);
  fill_tolerance_ = T(kFillTolerance);
  ghosts_.set_push_axes(image_push_axes<D>(scene.solver.gravity.data()));
  if (scene.debris.present) {
    if constexpr (D != 3) throw InputError(scene.file, "debris", "debris need a 3D scene");
    debris_ = std::make_unique<CpuDebris<D, T>>(scene_);
  }
  seed_particles();
  if (scene.inflow.present) {  // the buffer of the inflow boundary (solver/inflow.h)
    inflow_ = std::make_unique<InflowBoundary<D, T>>(scene_, spacing_, particle_arrays());
    inflow_->seed();
    n_ = x_[0].size();
    run_.mass = water_mass(vol_, rho_);
  }
  setup_boundaries();
  sort_particles();
  run_.start_audit(scene_, energy(), inflow_ ? inflow_->energy_scale() : 0.0);
  instruments_.sample(*this, 0.0, 0.0, true);
}

template <int D, typename T, bool Flip>
RunStatus MpmSolver<D, T, Flip>::step() {
  if (run_.status != RunStatus::kRunning) return run_.status;
  const double dt = run_.next_dt(scene_, dx_, c_);
  if (dt == 0) return run_.status;
  double t = omp_get_wtime();
  const auto lap = [&](int stage) {  // adds the time since the last lap to a stage (stage_seconds)
    const double now = omp_get_wtime();
    stage_s_[stage] += now - t;
    t = now;
  };
  if (needs_sort_) sort_particles();
  lap(kStageSort);
  p2g(T(dt));
  lap(kStageP2g);
  grid_update(T(dt));
  lap(kStageGrid);
  g2p(T(dt));
  lap(kStageG2p);
  const auto inflow = [&](double t0, double t1) { apply_inflow(t0, t1); };
  run_.end_step(scene_, dt, inflow_ != nullptr, inflow, instruments_, *this, load_impulse_);
  lap(kStageOther);
  return run_.status;
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::seed_particles() {
  spacing_ = particle_spacing(scene_);
  rho_ = scene_.fluid.density;
  // Water is not seeded inside a debris box: the box displaces it.
  const Seeds seeds =
      seed_water<D>(scene_, spacing_, displaced_by<D>(debris_ ? &debris_->bodies() : nullptr));
  n_ = seeds.size();
  for (int d = 0; d < D; ++d) {
    x_[d].assign(seeds.x[d].begin(), seeds.x[d].end());
    v_[d].assign(n_, T(0));
  }
  for (int k = 0; k < D * D; ++k) C_[k].assign(n_, T(0));
  e_.assign(seeds.strain.begin(), seeds.strain.end());
  vol_.assign(seeds.volume.begin(), seeds.volume.end());
  if (seeds.any_held) held_.assign(seeds.held.begin(), seeds.held.end());
  run_.mass = water_mass(vol_, rho_);
}

template <int D, typename T, bool Flip>
ParticleArrays<D, T> MpmSolver<D, T, Flip>::particle_arrays() {
  ParticleArrays<D, T> a;
  for (int d = 0; d < D; ++d) {
    a.x[d] = &x_[d];
    a.v[d] = &v_[d];
  }
  for (int k = 0; k < D * D; ++k) a.C[k] = &C_[k];
  a.e = &e_;
  a.vol = &vol_;
  a.held = &held_;
  a.tag = &tag_;
  return a;
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::sort_particles() {
  blocks_.sort(particle_arrays(), n_, grid_lo_, inv_dx_, dx_, walls_);
  fit_to_blocks();
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::fit_to_blocks() {
  if (has_sym_) {
    zone_.index(blocks_.gkeys);
    sym_acc_.resize(zone_.entries());
  }
  grid_.resize(blocks_.gkeys.size() * kNodes, kFlipChannels > 0);
  tiles_.resize(blocks_.pkeys.size() * kLanes * kTileNodes);
  tile_box_.resize(blocks_.pkeys.size());
  shares_.split(blocks_.pstart, blocks_.pkeys, blocks_.gkeys, omp_get_max_threads());
  boxes_current_ = false;
  needs_sort_ = false;
}

// The inflow moves, adds and removes particles after the step; the energy audit is told what it did.
template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::apply_inflow(double t0, double t1) {
  const auto change = inflow_->apply(t0, t1);
  boxes_current_ = false;  // it moved the buffer's particles
  run_.energy0 += change.energy;
  n_ = x_[0].size();
  if (change.structural) run_.mass = water_mass(vol_, rho_);
  needs_sort_ = needs_sort_ || change.structural;
}

template <int D, typename T, bool Flip>
void MpmSolver<D, T, Flip>::fail(const std::string& what) {
  run_.fail(what);
}

template <int D, typename T, bool Flip>
size_t MpmSolver<D, T, Flip>::grid_bytes() const {
  return grid_.bytes() + tiles_.capacity() * sizeof(T) + blocks_.bytes();
}

template <int D, typename T, bool Flip>
std::vector<std::pair<std::string, double>> MpmSolver<D, T, Flip>::stage_seconds() const {
  return {{"sort", stage_s_[kStageSort]},
          {"p2g", stage_s_[kStageP2g]},
          {"grid", stage_s_[kStageGrid]},
          {"g2p", stage_s_[kStageG2p]},
          {"instruments", stage_s_[kStageOther]}};
}

// The memory traffic of a step without a sort, counted from what the loops touch: P2G reads the particle
// state (x, v, C, e, vol) and writes its tile box; the grid update reads the tiles and writes the node
// arrays; G2P reads the nodes into its tile, reads x, e and vol and writes x, v, C and e.
template <int D, typename T, bool Flip>
double MpmSolver<D, T, Flip>::bytes_per_step() const {
  const double particles_read = double(n_) * sizeof(T) * (2 * D + D * D + 2);
  const double particles_g2p = double(n_) * sizeof(T) * ((D + 2) + (2 * D + D * D + 1));
  double tile_nodes = 0;
  for (const TileBox& b : tile_box_) {
    double v = 1;
    for (int d = 0; d < D; ++d) v *= b.hi[d] - b.lo[d];
    tile_nodes += v;
  }
  const double tiles = 2 * tile_nodes * kLanes * sizeof(T);  // written by P2G, read by the gather
  const double nodes = double(blocks_.gkeys.size()) * kNodes;
  const double grid = nodes * ((D + 3 + kFlipChannels) * sizeof(T) + 1) + tile_nodes * ((D + 2) * sizeof(T) + 1);
  return particles_read + particles_g2p + tiles + grid;
}

#define FLUME_INSTANTIATE(D, T, Flip)                                                                \
  template MpmSolver<D, T, Flip>::MpmSolver(const Scene&, const SimulationOptions&);                 \
  template RunStatus MpmSolver<D, T, Flip>::step();                                                  \
  template void MpmSolver<D, T, Flip>::seed_particles();                                             \
  template ParticleArrays<D, T> MpmSolver<D, T, Flip>::particle_arrays();                            \
  template void MpmSolver<D, T, Flip>::sort_particles();                                             \
  template void MpmSolver<D, T, Flip>::fit_to_blocks();                                              \
  template void MpmSolver<D, T, Flip>::apply_inflow(double, double);                                 \
  template void MpmSolver<D, T, Flip>::fail(const std::string&);                                     \
  template size_t MpmSolver<D, T, Flip>::grid_bytes() const;                                         \
  template std::vector<std::pair<std::string, double>> MpmSolver<D, T, Flip>::stage_seconds() const; \
  template double MpmSolver<D, T, Flip>::bytes_per_step() const;
FLUME_MPM_SOLVER_VARIANTS(FLUME_INSTANTIATE)
#undef FLUME_INSTANTIATE

}  // namespace mpm

// This copy's factory (solver/cpu_kernels.h).
std::unique_ptr<Simulation> FLUME_KERNELS_ENTRY(make_cpu_simulation)(const Scene& scene, const SimulationOptions& options) {
  const bool f = scene.solver.precision == Precision::kFloat;
  if (scene.solver.flip > 0) {  // FLIP's old velocity in the scatter: a solver of its own (kFlipChannels)
    if (scene.dimension == 2) {
      if (f) return std::make_unique<mpm::MpmSolver<2, float, true>>(scene, options);
      return std::make_unique<mpm::MpmSolver<2, double, true>>(scene, options);
    }
    if (f) return std::make_unique<mpm::MpmSolver<3, float, true>>(scene, options);
    return std::make_unique<mpm::MpmSolver<3, double, true>>(scene, options);
  }
  if (scene.dimension == 2) {
    if (f) return std::make_unique<mpm::MpmSolver<2, float, false>>(scene, options);
    return std::make_unique<mpm::MpmSolver<2, double, false>>(scene, options);
  }
  if (f) return std::make_unique<mpm::MpmSolver<3, float, false>>(scene, options);
  return std::make_unique<mpm::MpmSolver<3, double, false>>(scene, options);
}

}  // namespace flume
