// The CPU (OpenMP) backend of the MLS-MPM solver on a block-sparse grid.
//
// Layout. Particles are stored as structure-of-arrays and kept sorted by the grid block that holds their
// stencil's base node. Only grid blocks within one block of a particle block exist, so memory and work
// follow the water, not the domain box.
//
// Race-free scatter by design. Each particle block scatters (P2G) into its own tile of kTile^D nodes, a
// private buffer no other thread touches; each grid block then gathers the overlapping parts of the tiles
// of its 3^D neighbouring particle blocks, in a fixed order. No atomics, and the result does not depend on
// the number of threads. Particles may drift up to one cell from the block they were sorted into before a
// re-sort is needed, which is what the tile's margin allows for.
#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

#include "common/errors.h"
#include "solver/interleave_axes.h"
#include "solver/block_sort.h"
#include "solver/checkpoint.h"
#include "solver/debris_coupling.h"
#include "solver/inflow.h"
#include "solver/instruments.h"
#include "solver/mpm/audit.h"
#include "solver/mpm/blocks_k.h"
#include "solver/mpm/boundaries.h"
#include "solver/mpm/diagnostics_k.h"
#include "solver/mpm/launch.h"
#include "solver/mpm/node_k.h"
#include "solver/mpm/particle_k.h"
#include "solver/mpm/symmetry_zone.h"
#include "solver/mpm/tiles.h"
#include "solver/mpm_kernels.h"
#include "solver/seeding.h"
#include "solver/simulation.h"
#include "solver/symmetry.h"

namespace flume {
namespace mpm {
namespace {

constexpr int kPad = kBlock;  // nodes of padding below the domain, so every node index is non-negative

template <int D, typename T>
class MpmSolver final : public Simulation {
  static constexpr int kNodes = mpm::Pow<D>::of(kBlock);
  static constexpr int kTileNodes = mpm::Pow<D>::of(kTile);
  static constexpr int kNbr = mpm::Pow<D>::of(3);
  static constexpr int kChannels = D + 3;  // mass, momentum (D), mass-weighted strain J - 1, particle volume
  // Tiles and the grid gather hold a node's channels side by side, padded to one SIMD vector (Eigen packet):
  // a particle's contribution to a node is then one vector multiply-add, not kChannels scalar ones. G2P's
  // tile holds per node the velocity, the free-node weight 1 (0 on a wall node) and the strain and fill times
  // it, so one vector multiply-add per node gathers all of them.
  static constexpr int kLanes = 8;
  static constexpr int kBatch = 32;  // particles per pass of p2g's two-pass loop
  static_assert(kChannels <= kLanes && D + 3 <= kLanes, "channels must fit the lanes");
  using Lane = Eigen::Array<T, kLanes, 1>;
  using LaneMap = Eigen::Map<Lane>;
  using ConstLaneMap = Eigen::Map<const Lane>;

 public:
  MpmSolver(const Scene& scene, const SimulationOptions& options)
      : scene_(scene), instruments_(scene_) {
    if (options.threads > 0) omp_set_num_threads(options.threads);
    dx_ = scene.solver.dx;
    inv_dx_ = T(1) / T(dx_);
    for (int d = 0; d < D; ++d) {
      grid_lo_[d] = scene.domain_lo[d] - kPad * dx_;
      gravity_[d] = T(scene.solver.gravity[d]);
    }
    const auto& f = scene.fluid;
    mu_ = T(f.viscosity);
    psi_ = T(f.jbar_psi);
    law_ = mpm::TaitLaw<T>(T(f.bulk_modulus), T(f.gamma));
    law_d_ = mpm::TaitLaw<double>(double(law_.K), double(law_.gamma));
    fill_tolerance_ = T(mpm::kFillTolerance);
    for (int d = 0; d < D; ++d) strain_slope_[d] = T(-f.density * scene.solver.gravity[d] / f.bulk_modulus);
    c_ = mpm::sound_speed(f.bulk_modulus, f.density);
    push_axes_ = mpm::image_push_axes<D>(scene.solver.gravity.data());
    if (scene.debris.present) {
      if constexpr (D != 3) throw InputError(scene.file, "debris", "debris need a 3D scene");
      debris_ = std::make_unique<DebrisCoupling>(scene_);
    }
    seed_particles();
    if (scene.inflow.present) {  // the buffer of the inflow boundary (solver/inflow.h)
      inflow_ = std::make_unique<InflowBoundary<D, T>>(scene_, spacing_, particle_arrays());
      inflow_->seed();
      n_ = x_[0].size();
      mass_ = water_mass(vol_, rho_);
    }
    setup_boundaries();
    sort_particles();
    const Energy e = energy();
    energy0_ = e.total();
    energy_slack_ = mpm::energy_slack(scene_, mass_, e.kinetic);
    if (inflow_) energy_slack_ = std::max(energy_slack_, inflow_->energy_scale());
    instruments_.sample(*this, 0.0, 0.0, true);
  }

  RunStatus step() override {
    if (status_ != RunStatus::kRunning) return status_;
    double dt = std::min(scene_.solver.max_dt, scene_.solver.cfl * dx_ / (c_ + max_speed_));
    const double remaining = scene_.solver.end_time - time_;
    if (dt >= remaining) dt = remaining;
    if (!(dt > 0)) {
      status_ = RunStatus::kOk;
      return status_;
    }
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
    time_ += dt;
    dt_ = dt;
    ++steps_;
    if (inflow_ && status_ == RunStatus::kRunning) apply_inflow(time_ - dt, time_);
    if (status_ == RunStatus::kUnstable) {
      instruments_.sample(*this, time_, dt, true);
      return status_;
    }
    instruments_.add_impulses(load_impulse_, dt);
    instruments_.sample(*this, time_, dt, false);
    lap(kStageOther);
    if (time_ >= scene_.solver.end_time - 1e-12) status_ = RunStatus::kOk;
    return status_;
  }

  double time() const override { return time_; }
  double last_dt() const override { return dt_; }
  long steps() const override { return steps_; }
  size_t particle_count() const override { return n_; }
  double total_mass() const override { return mass_; }
  const Record& record() const override { return instruments_.record(); }
  const std::string& message() const override { return message_; }

  void particle_positions(std::vector<double>& xyz) const override {
    interleave_axes<D>(x_, n_, xyz);
  }
  void particle_velocities(std::vector<double>& vel) const override {
    interleave_axes<D>(v_, n_, vel);
  }
  void particle_pressures(std::vector<double>& p) const override {
    p.resize(n_);
    for (size_t i = 0; i < n_; ++i) p[i] = law_d_.pressure(double(e_[i]));
  }
  size_t grid_bytes() const override {
    size_t b = (gm_.capacity() + ge_.capacity() + gfill_.capacity()) * sizeof(T) + tiles_.capacity() * sizeof(T);
    for (int d = 0; d < D; ++d) b += gv_[d].capacity() * sizeof(T);
    b += (gkeys_.capacity() + pkeys_.capacity()) * sizeof(uint64_t);
    b += (p_nbr_.capacity() + g_nbr_.capacity() + g_bnd_.capacity()) * sizeof(int32_t);
    return b;
  }
  size_t active_blocks() const override { return gkeys_.size(); }
  size_t particle_bytes() const override { return n_ * sizeof(T) * (2 * D + D * D + 2); }
  std::vector<std::pair<std::string, double>> stage_seconds() const override {
    return {{"sort", stage_s_[kStageSort]},
            {"p2g", stage_s_[kStageP2g]},
            {"grid", stage_s_[kStageGrid]},
            {"g2p", stage_s_[kStageG2p]},
            {"instruments", stage_s_[kStageOther]}};
  }
  // The memory traffic of a step without a sort, counted from what the loops touch: P2G reads the particle
  // state (x, v, C, e, vol) and writes its tile box; the grid update reads the tiles and writes the node arrays;
  // G2P reads the nodes into its tile, reads x, e and vol and writes x, v, C and e.
  double bytes_per_step() const override {
    const double particles_read = double(n_) * sizeof(T) * (2 * D + D * D + 2);
    const double particles_g2p = double(n_) * sizeof(T) * ((D + 2) + (2 * D + D * D + 1));
    double tile_nodes = 0;
    for (const TileBox& b : tile_box_) {
      double v = 1;
      for (int d = 0; d < D; ++d) v *= b.hi[d] - b.lo[d];
      tile_nodes += v;
    }
    const double tiles = 2 * tile_nodes * kLanes * sizeof(T);  // written by P2G, read by the gather
    const double nodes = double(gkeys_.size()) * kNodes;
    const double grid = nodes * ((D + 3) * sizeof(T) + 1) + tile_nodes * ((D + 2) * sizeof(T) + 1);
    return particles_read + particles_g2p + tiles + grid;
  }

  void momentum(double linear[3], double angular[3]) const override {
    for (int d = 0; d < 3; ++d) linear[d] = angular[d] = 0;
    for (size_t i = 0; i < n_; ++i) {
      double x[D], v[D], C[D * D];
      for (int d = 0; d < D; ++d) {
        x[d] = x_[d][i];
        v[d] = v_[d][i];
      }
      for (int k = 0; k < D * D; ++k) C[k] = C_[k][i];
      mpm::add_particle_momentum<D>(rho_ * double(vol_[i]), dx_, x, v, C, linear, angular);
    }
  }

  void set_rigid_velocity(const double v0[3], const double omega[3], const double centre[3]) override {
    for (size_t i = 0; i < n_; ++i) {
      double r[D], v[D], C[D * D];
      for (int d = 0; d < D; ++d) r[d] = x_[d][i] - centre[d];
      mpm::rigid_motion<D>(v0, omega, r, v, C);
      for (int d = 0; d < D; ++d) v_[d][i] = T(v[d]);
      for (int k = 0; k < D * D; ++k) C_[k][i] = T(C[k]);
    }
    max_speed_ = 0;
    for (size_t i = 0; i < n_; ++i) {
      double s2 = 0;
      for (int d = 0; d < D; ++d) s2 += double(v_[d][i]) * v_[d][i];
      max_speed_ = std::max(max_speed_, std::sqrt(s2));
    }
    energy0_ = energy().total();
    double ke = energy().kinetic;
    energy_slack_ = std::max(energy_slack_, 0.01 * ke);
  }

  const DebrisCoupling* debris() const override { return debris_.get(); }
  DebrisCoupling* debris() override { return debris_.get(); }

  // Everything a step reads that an earlier step wrote: the particles, the clock, the step-size control, the
  // energy audit, the instruments, the inflow and the debris, and the block each particle was last sorted into.
  // The block lists and the grid are rebuilt from those, so a resumed run repeats the uninterrupted one step
  // for step, to the bit.
  void checkpoint(StateArchive& ar) override {
    ar.section(std::string("mpm ") + std::to_string(D) + "D " + (sizeof(T) == 4 ? "float" : "double"));
    for (int d = 0; d < D; ++d) {
      ar(x_[d]);
      ar(v_[d]);
    }
    for (auto& c : C_) ar(c);
    ar(e_);
    ar(vol_);
    ar(held_);
    ar(tag_);
    ar.fields(time_, dt_, max_speed_, steps_, energy0_, energy_slack_, last_energy_, mass_, status_,
              message_);
    // The block each particle was sorted into: between sorts a particle may drift into the next block's tile
    // margin without a re-sort, so its block is not a function of its position.
    ar.fields(needs_sort_, sort_key_);
    instruments_.checkpoint(ar);
    ar.expect("inflow", inflow_ ? 1 : 0);
    if (inflow_) inflow_->checkpoint(ar);
    ar.expect("debris", debris_ ? 1 : 0);
    if (debris_) debris_->checkpoint(ar);
    if (ar.loading()) {
      n_ = x_[0].size();
      const auto bad = [&](const std::vector<T>& a) { return a.size() != n_; };
      bool mismatch = bad(e_) || bad(vol_) || (!held_.empty() && bad(held_)) || (!tag_.empty() && bad(tag_));
      for (int d = 0; d < D; ++d) mismatch = mismatch || bad(x_[d]) || bad(v_[d]);
      for (auto& c : C_) mismatch = mismatch || bad(c);
      if (mismatch) ar.fail("particles", "particle arrays of different lengths");
      if (status_ == RunStatus::kUnstable) ar.fail("status", "the checkpointed run had gone unstable");
      // A finished run resumed to a later end time runs on.
      status_ = time_ < scene_.solver.end_time - 1e-12 ? RunStatus::kRunning : RunStatus::kOk;
      if (!needs_sort_) {
        if (sort_key_.size() != n_) ar.fail("particles", "block keys for a different particle count");
        build_blocks();
      }
    }
  }

  // --- read access for the instruments ---
  int dim() const { return D; }
  size_t n() const { return n_; }
  T x(int d, size_t i) const { return x_[d][i]; }
  T v(int d, size_t i) const { return v_[d][i]; }
  T volume(size_t i) const { return vol_[i]; }  // reference volume: the particle's mass over rho
  double max_speed() const { return max_speed_; }

  struct Energy {
    double kinetic = 0, potential = 0, elastic = 0;
    double debris = 0;  // the boxes' kinetic and potential energy
    double total() const { return kinetic + potential + elastic + debris; }
  };
  Energy energy() const {
    double ke = 0, pe = 0, el = 0;
#pragma omp parallel for reduction(+ : ke, pe, el) schedule(static)
    for (size_t i = 0; i < n_; ++i) {
      double v2 = 0, gx = 0;
      for (int d = 0; d < D; ++d) {
        v2 += double(v_[d][i]) * v_[d][i];
        gx += double(gravity_[d]) * x_[d][i];
      }
      const double V = vol_[i], mp = rho_ * V;
      ke += 0.5 * mp * v2;
      pe -= mp * gx;
      el += V * law_d_.energy_density(double(e_[i]));
    }
    return {ke, pe, el, debris_ ? debris_->energy() : 0.0};
  }

 private:
  void seed_particles() {
    const int per_axis = static_cast<int>(std::lround(std::pow(scene_.solver.ppc, 1.0 / D)));
    spacing_ = dx_ / per_axis;
    rho_ = scene_.fluid.density;
    // Water is not seeded inside a debris box: the box displaces it.
    const Seeds seeds = seed_water<D>(scene_, spacing_, displaced_by<D>(debris_.get()));
    n_ = seeds.size();
    for (int d = 0; d < D; ++d) {
      x_[d].assign(seeds.x[d].begin(), seeds.x[d].end());
      v_[d].assign(n_, T(0));
    }
    for (int k = 0; k < D * D; ++k) C_[k].assign(n_, T(0));
    e_.assign(seeds.strain.begin(), seeds.strain.end());
    vol_.assign(seeds.volume.begin(), seeds.volume.end());
    if (seeds.any_held) held_.assign(seeds.held.begin(), seeds.held.end());
    mass_ = water_mass(vol_, rho_);
  }

  void setup_boundaries() {
    walls_ = mpm::scene_walls<D, T>(scene_);
    has_sym_ = mpm::scene_symmetry_plane<D>(scene_, grid_lo_, dx_, sym_);
    zone_ = mpm::SymmetryZone<D>(sym_);
    if (has_sym_ && debris_)
      throw InputError(scene_.file, "boundaries", "a symmetry plane cannot be used with debris (the bodies would "
                                                  "need their mirror images): model the full span");
    container_ = mpm::scene_container<D, T>(scene_);
    subcell_rate0_ = mpm::subcell_rate0(c_, dx_);
    load_impulse_.assign(walls_.size() * D, 0.0);
  }

  // Bins particles by the block of their stencil's base node and rebuilds the sparse block lists.
  void sort_particles() {
    // The work arrays persist between sorts: fresh ones each time cost a page fault per 4 kB touched.
    std::vector<uint64_t>& key = sort_key_;
    key.resize(n_);
    mpm::parallel_for(n_, [&](size_t i) {
      T xg[D];
      for (int d = 0; d < D; ++d) xg[d] = (x_[d][i] - T(grid_lo_[d])) * inv_dx_;
      key[i] = mpm::particle_block_key<D>(xg);
    });
    if (!std::is_sorted(key.begin(), key.end())) {
      std::vector<uint32_t>& order = sort_order_;
      order.resize(n_);
      stable_order_by_key(key, order, sort_work_);  // std::stable_sort's order, in parallel (block_sort.h)
      auto permute = [&](std::vector<T>& a) {
        std::vector<T>& tmp = sort_scratch_;
        tmp.resize(n_);
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n_; ++i) tmp[i] = a[order[i]];
        a.swap(tmp);
      };
      for (int d = 0; d < D; ++d) {
        permute(x_[d]);
        permute(v_[d]);
      }
      for (int k = 0; k < D * D; ++k) permute(C_[k]);
      permute(e_);
      permute(vol_);
      if (!held_.empty()) permute(held_);
      if (!tag_.empty()) permute(tag_);
      std::vector<uint64_t>& sorted = sort_key_scratch_;
      sorted.resize(n_);
#pragma omp parallel for schedule(static)
      for (size_t i = 0; i < n_; ++i) sorted[i] = key[order[i]];
      key.swap(sorted);
    }
    build_blocks();
  }

  // The particle blocks, grid blocks and their neighbour and boundary lists, from the particles' block keys
  // (sort_key_, in particle order) as the last sort assigned them.
  void build_blocks() {
    const std::vector<uint64_t>& key = sort_key_;
    // Particle blocks and their particle ranges.
    pkeys_.clear();
    pstart_.clear();
    for (size_t i = 0; i < n_; ++i)
      if (i == 0 || key[i] != key[i - 1]) {
        pkeys_.push_back(key[i]);
        pstart_.push_back(static_cast<uint32_t>(i));
      }
    pstart_.push_back(static_cast<uint32_t>(n_));
    // Grid blocks: the 3^D neighbourhood of every particle block.
    std::vector<uint64_t> g;
    g.reserve(pkeys_.size() * kNbr);
    for (uint64_t k : pkeys_) {
      int b[D];
      unpack_key<D>(k, b);
      for (int o = 0; o < kNbr; ++o) {
        int nb[D];
        mpm::neighbour_block<D>(b, o, nb);
        g.push_back(pack_key<D>(nb));
      }
    }
    std::sort(g.begin(), g.end());
    g.erase(std::unique(g.begin(), g.end()), g.end());
    gkeys_.swap(g);
    if (has_sym_) index_symmetry_blocks();
    auto find = [](const std::vector<uint64_t>& v, uint64_t k) -> int32_t {
      auto it = std::lower_bound(v.begin(), v.end(), k);
      return it != v.end() && *it == k ? static_cast<int32_t>(it - v.begin()) : -1;
    };
    p_nbr_.assign(pkeys_.size() * kNbr, -1);
    g_nbr_.assign(gkeys_.size() * kNbr, -1);
#pragma omp parallel for schedule(static)
    for (size_t p = 0; p < pkeys_.size(); ++p) {
      int b[D];
      unpack_key<D>(pkeys_[p], b);
      for (int o = 0; o < kNbr; ++o) {
        int nb[D];
        mpm::neighbour_block<D>(b, o, nb);
        p_nbr_[p * kNbr + o] = find(gkeys_, pack_key<D>(nb));
      }
    }
#pragma omp parallel for schedule(static)
    for (size_t gi = 0; gi < gkeys_.size(); ++gi) {
      int b[D];
      unpack_key<D>(gkeys_[gi], b);
      for (int o = 0; o < kNbr; ++o) {
        int nb[D];
        mpm::neighbour_block<D>(b, o, nb);
        g_nbr_[gi * kNbr + o] = find(pkeys_, pack_key<D>(nb));
      }
    }
    // Boundaries that can reach each grid block (so the grid update tests only those): counted per block in
    // parallel, then listed at the blocks' offsets (a serial pass over blocks x walls showed in the Waseda
    // apron's profile, which re-sorts almost every step).
    const auto reaches = [&](size_t gi, size_t w) {
      int b[D];
      unpack_key<D>(gkeys_[gi], b);
      T centre[D];
      T half_diag = 0;
      for (int d = 0; d < D; ++d) {
        centre[d] = T(grid_lo_[d] + (b[d] * kBlock + 0.5 * (kBlock - 1)) * dx_);
        half_diag += T(0.25 * (kBlock * dx_) * (kBlock * dx_));
      }
      half_diag = std::sqrt(half_diag);
      T n[D];
      return wall_distance(walls_[w], centre, n) <= half_diag + T(dx_);
    };
    g_bnd_start_.assign(gkeys_.size() + 1, 0);
#pragma omp parallel for schedule(static)
    for (size_t gi = 0; gi < gkeys_.size(); ++gi) {
      uint32_t count = 0;
      for (size_t w = 0; w < walls_.size(); ++w) count += reaches(gi, w);
      g_bnd_start_[gi + 1] = count;
    }
    for (size_t gi = 0; gi < gkeys_.size(); ++gi) g_bnd_start_[gi + 1] += g_bnd_start_[gi];
    g_bnd_.resize(g_bnd_start_.back());
#pragma omp parallel for schedule(static)
    for (size_t gi = 0; gi < gkeys_.size(); ++gi) {
      uint32_t q = g_bnd_start_[gi];
      for (size_t w = 0; w < walls_.size(); ++w)
        if (reaches(gi, w)) g_bnd_[q++] = static_cast<int32_t>(w);
    }
    const size_t nodes = gkeys_.size() * kNodes;
    gm_.resize(nodes);
    ge_.resize(nodes);
    gfill_.resize(nodes);
    gwall_.resize(nodes);
    for (int d = 0; d < D; ++d) gv_[d].resize(nodes);
    tiles_.resize(pkeys_.size() * kLanes * kTileNodes);
    tile_box_.resize(pkeys_.size());
    needs_sort_ = false;
  }

  struct Ghost {
    size_t idx = 0;       // the ghost node
    int offset[D] = {};   // the reflection's offset in nodes, then (after the walls) the mirror node
    unsigned axes = 0;    // the normal axes: kept; the others are exchanged with the mirror
    T vpre[D] = {};       // the ghost's velocity from the particles alone (mpm::ghost_exchange)
    int wall = -1;        // the scene wall whose load takes the image's push (-1: the domain box)
    double load_weight = 1;  // 1/2 on a symmetry plane (the whole's load there is twice the half's)
  };
  using Wall = mpm::Wall<D, T>;
  T wall_distance(const Wall& w, const T* x, T* n) const {
    T a[D], b[D];  // in T, as the node update's reach test always took them
    for (int d = 0; d < D; ++d) {
      a[d] = T(w.a[d]);
      b[d] = T(w.b[d]);
    }
    return w.box ? mpm::box_distance<D>(x, a, b, n) : mpm::half_space_distance<D>(x, a, b, n);
  }
  using TileNode = mpm::TileNode;
  using TileBox = mpm::TileBox<D>;
  TileBox tile_box(long p, const T* lo_grid, T inv_dx) const {
    int blk[D];
    unpack_key<D>(pkeys_[p], blk);
    const T* x[D];
    for (int d = 0; d < D; ++d) x[d] = x_[d].data();
    return mpm::tile_box<D>(blk, x, pstart_[p], pstart_[p + 1], lo_grid, inv_dx);
  }

  // P2G: each particle block scatters mass, momentum (with the MLS-MPM stress term) and mass-weighted strain J - 1
  // into its private tile, node-major with kLanes channels per node.
  void p2g(T dt) {
    const T dx = T(dx_);
    const T rho = T(rho_);
    const T stress_scale = -dt * T(4) * inv_dx_ * inv_dx_;  // times the particle's reference volume
    const mpm::TaitLaw<T> law = law_;  // locals: the tile stores could alias members, which are reloaded then
    const T mu = mu_, inv_dx = inv_dx_;
    T slope_h[D], lo_grid[D];
    for (int d = 0; d < D; ++d) {
      slope_h[d] = strain_slope_[d];
      lo_grid[d] = T(grid_lo_[d]);
    }
    const T lift = T(double(dt) * scene_.basin.forcing.hold(time_) * std::fabs(scene_.solver.gravity[D - 1]));
    const long nblocks = static_cast<long>(pkeys_.size());
    Lane unit[kLanes];
    for (int c = 0; c < kLanes; ++c) unit[c] = Eigen::Matrix<T, kLanes, 1>::Unit(c).array();
#pragma omp parallel for schedule(dynamic, 4)
    for (long p = 0; p < nblocks; ++p) {
      T* tile = &tiles_[static_cast<size_t>(p) * kLanes * kTileNodes];
      const TileBox box = tile_box(p, lo_grid, inv_dx);
      tile_box_[p] = box;
      mpm::for_each_box_row<D>(box,
                               [&](int a, int len) { std::fill_n(tile + a * kLanes, len * kLanes, T(0)); });
      int blk[D], origin[D];
      unpack_key<D>(pkeys_[p], blk);
      for (int d = 0; d < D; ++d) origin[d] = blk[d] * kBlock - 1;
      // Two passes per batch of particles. The first computes each particle's weights and what its nodes
      // receive into plain arrays across the batch; the second builds the lane vectors and scatters. The
      // scalar set-up (three fifths of P2G in perf) then runs back to back for 32 particles instead of
      // queueing behind each one's 27-node scatter (docs/solver.md, "Measurements behind the constants").
      // Plain pointers to the particle arrays: GCC does not vectorise a loop that loads a vector's data pointer
      // out of `this` in its body (x_[d][i]), and the set-up loop below then ran scalar.
      const T *xs[D], *vs[D], *Cs[D * D];
      for (int d = 0; d < D; ++d) {
        xs[d] = x_[d].data();
        vs[d] = v_[d].data();
      }
      for (int k = 0; k < D * D; ++k) Cs[k] = C_[k].data();
      const T* es = e_.data();
      const T* vols = vol_.data();
      for (uint32_t b0 = pstart_[p]; b0 < pstart_[p + 1]; b0 += kBatch) {
        const int nb = static_cast<int>(std::min<uint32_t>(kBatch, pstart_[p + 1] - b0));
        alignas(64) T bw[D][3][kBatch], bat0[kChannels][kBatch], bslope[D][D][kBatch], bp[kBatch];
        alignas(64) int brel[D][kBatch];
        const T *bx[D], *bv[D], *bC[D * D], *be = es + b0, *bvol = vols + b0;  // the batch's particles
        for (int d = 0; d < D; ++d) {
          bx[d] = xs[d] + b0;
          bv[d] = vs[d] + b0;
        }
        for (int k = 0; k < D * D; ++k) bC[k] = Cs[k] + b0;
#pragma omp simd
        for (int j = 0; j < nb; ++j) bp[j] = law.pressure_series(be[j]);
        for (int j = 0; j < nb; ++j)
          if (!law.in_series(be[j])) bp[j] = law.pressure_exact(be[j]);
        // The stencil weights in a loop of their own per axis (as G2P), then the particle's terms. Both loops
        // vectorise across the batch (-fno-trapping-math for the float-to-int base); with `omp simd` on them
        // GCC 12 gave up on both.
        alignas(64) T bf[D][kBatch];
        for (int d = 0; d < D; ++d) {
          for (int j = 0; j < nb; ++j) {
            T w[3];
            brel[d][j] = mpm::stencil_base((bx[d][j] - lo_grid[d]) * inv_dx, bf[d][j]) - origin[d];
            mpm::bspline_weights(bf[d][j], w);
            for (int c = 0; c < 3; ++c) bw[d][c][j] = w[c];
          }
        }
        for (int j = 0; j < nb; ++j) {
          T f[D], xp[D];
          for (int d = 0; d < D; ++d) {
            xp[d] = bx[d][j];
            f[d] = bf[d][j];
          }
          T Cp[D * D], vp[D], A[D * D], mom0[D], strain, volume;
          for (int k = 0; k < D * D; ++k) Cp[k] = bC[k][j];
          for (int a = 0; a < D; ++a) vp[a] = bv[a][j];
          const T V = bvol[j], m = rho * V;
          mpm::p2g_particle<D>(bp[j], Cp, be[j], V, m, vp, f, xp, dx, mu, stress_scale, slope_h, A, mom0,
                               strain, volume);
          // What node (base + i) receives, before its weight: the channels at i = 0 plus i_b times slope[b].
          for (int a = 0; a < D; ++a) {
            bat0[1 + a][j] = mom0[a];
            for (int b = 0; b < D; ++b) bslope[b][a][j] = A[a * D + b] * dx;
          }
          bat0[0][j] = m;
          bat0[1 + D][j] = strain;
          bat0[2 + D][j] = volume;
        }
        // The vacuum's hold: an upward force f(t) m |g| on the held water.
        if (!held_.empty())
          for (int j = 0; j < nb; ++j) bat0[D][j] += held_[b0 + j] * lift * bat0[0][j];
        for (int j = 0; j < nb; ++j) {
          // The lane vectors are summed from the unit vectors rather than written lane by lane: a vector load
          // right after scalar stores to the same place stalls (store forwarding fails).
          Lane at0 = bat0[0][j] * unit[0], slope[D];
          for (int c = 1; c < kChannels; ++c) at0 += bat0[c][j] * unit[c];
          for (int b = 0; b < D; ++b) {
            slope[b] = bslope[b][0][j] * unit[1];
            for (int a = 1; a < D; ++a) slope[b] += bslope[b][a][j] * unit[1 + a];
          }
          if constexpr (D == 2) {
            for (int i0 = 0; i0 < 3; ++i0) {
              const Lane r0 = at0 + T(i0) * slope[0];
              const int row = (brel[0][j] + i0) * kTile + brel[1][j];
              for (int i1 = 0; i1 < 3; ++i1)
                LaneMap(tile + (row + i1) * kLanes) += (bw[0][i0][j] * bw[1][i1][j]) * (r0 + T(i1) * slope[1]);
            }
          } else {
            // Node (i0, i1, i2) receives w0 w1 w2 (at0 + i0 s0 + i1 s1 + i2 s2). The last axis' weight goes into
            // the vectors once per particle (P, Q0, Q1 below), so that a node costs one vector multiply-add to
            // form its value and one to add it, with no scalar weight product and broadcast per node.
            Lane P[3], Q0[3], Q1[3];
            for (int i2 = 0; i2 < 3; ++i2) {
              const T w2 = bw[2][i2][j];
              P[i2] = w2 * (at0 + T(i2) * slope[2]);
              Q0[i2] = w2 * slope[0];
              Q1[i2] = w2 * slope[1];
            }
            for (int i0 = 0; i0 < 3; ++i0) {
              Lane R0[3];
              for (int i2 = 0; i2 < 3; ++i2) R0[i2] = P[i2] + T(i0) * Q0[i2];
              for (int i1 = 0; i1 < 3; ++i1) {
                const T w01 = bw[0][i0][j] * bw[1][i1][j];
                const int row = ((brel[0][j] + i0) * kTile + brel[1][j] + i1) * kTile + brel[2][j];
                for (int i2 = 0; i2 < 3; ++i2)
                  LaneMap(tile + (row + i2) * kLanes) += w01 * (R0[i2] + T(i1) * Q1[i2]);
              }
            }
          }
        }
      }
    }
  }

  // One grid node from what the particles gave it (its lanes `acc`): momentum to velocity, gravity, the walls
  // (their loads weighted by `load_weight`), its ghost pairing and the debris coupling.
  void update_node(const Lane& acc, long g, size_t idx, const int* node, bool near_debris, double load_weight, T dt,
                   T inv_cell_volume, double* my_impulse, std::vector<CouplingNode>* my_coupling,
                   std::vector<Ghost>* my_ghosts) {
    const T m = acc[0];
    if (m <= T(0)) {
      gm_[idx] = T(0);
      ge_[idx] = T(0);
      gfill_[idx] = T(0);
      gwall_[idx] = 0;
      for (int d = 0; d < D; ++d) gv_[d][idx] = T(0);
      return;
    }
    T v[D];
    for (int d = 0; d < D; ++d) v[d] = acc[1 + d] / m + dt * gravity_[d];
    // The ghost's image reflects the particles' momentum only, not gravity's (mpm::ghost_exchange).
    Ghost ghost;
    for (int d = 0; d < D; ++d) ghost.vpre[d] = acc[1 + d] / m;
    double xn[D];
    for (int d = 0; d < D; ++d) xn[d] = mpm::node_coordinate(grid_lo_[d], node[d], dx_);
    mpm::GhostSearch<D> found;
    uint8_t on_wall = mpm::apply_boundaries<D>(
        xn, m, v, dt, load_weight, dx_, subcell_rate0_, walls_.data(), g_bnd_.data() + g_bnd_start_[g],
        static_cast<int>(g_bnd_start_[g + 1] - g_bnd_start_[g]), container_, my_impulse, found);
    if (found.found()) {
      ghost.idx = idx;
      ghost.load_weight = load_weight;
      ghost.axes = found.axes;
      ghost.wall = found.wall;
      for (int d = 0; d < D; ++d) ghost.offset[d] = found.offset[d] + node[d];  // the mirror node itself
      my_ghosts->push_back(ghost);
    }
    // Debris: the node is a moving-wall node of the box it lies in; its velocity is set after every
    // node is known, by the implicit exchange (debris_coupling.h).
    if (near_debris) {
      CouplingNode c;
      const auto& views = debris_->views();
      const T e_node = acc[1 + D] / m;
      if (mpm::coupling_node<D, T>(views.data(), debris_->bounding_radii().data(), int(views.size()), xn,
                                   coupling_band_ * dx_, idx, m, e_node, v, law_d_, strain_slope_, c)) {
        my_coupling->push_back(c);
        on_wall = 1;
      }
    }
    gm_[idx] = m;
    ge_[idx] = acc[1 + D] / m;
    gfill_[idx] = acc[2 + D] * inv_cell_volume;
    gwall_[idx] = on_wall;
    for (int d = 0; d < D; ++d) gv_[d][idx] = v[d];
  }

  // Gathers the tiles into the grid blocks, then turns momentum into velocity, adds gravity and applies the
  // boundary conditions. Load cells sum the impulse the boundary gives the water at its nodes.
  void grid_update(T dt) {
    const T inv_cell_volume = T(1) / T(std::pow(dx_, D));
    const long ngb = static_cast<long>(gkeys_.size());
    const int nthreads = omp_get_max_threads();
    std::vector<double> impulse(static_cast<size_t>(nthreads) * walls_.size() * D, 0.0);
    if (debris_) coupling_.assign(nthreads, {});
    ghosts_.resize(nthreads);
#pragma omp parallel
    {
      double* my_impulse = impulse.data() + static_cast<size_t>(omp_get_thread_num()) * walls_.size() * D;
      std::vector<CouplingNode>* my_coupling = debris_ ? &coupling_[omp_get_thread_num()] : nullptr;
      std::vector<Ghost>* my_ghosts = &ghosts_[omp_get_thread_num()];
      my_ghosts->clear();
#pragma omp for schedule(dynamic, 8)
      for (long g = 0; g < ngb; ++g) {
        Lane acc[kNodes];
        for (int k = 0; k < kNodes; ++k) acc[k] = Lane::Zero();
        for (int o = 0; o < kNbr; ++o) {
          const int32_t p = g_nbr_[g * kNbr + o];
          if (p < 0) continue;
          // Block offset of the particle block relative to this grid block, per axis.
          int off[D];
          for (int d = D - 1, r = o; d >= 0; --d, r /= 3) off[d] = -((r % 3) - 1);
          // Local node l of this block is tile node a = l + 1 + kBlock * off on each axis.
          int lo[D], hi[D];
          const TileBox& box = tile_box_[p];
          bool empty = false;
          for (int d = 0; d < D; ++d) {
            const int shift = 1 + kBlock * off[d];
            lo[d] = std::max(0, box.lo[d] - shift);
            hi[d] = std::min(kBlock, box.hi[d] - shift);
            empty |= lo[d] >= hi[d];
          }
          if (empty) continue;
          const T* tile = &tiles_[static_cast<size_t>(p) * kLanes * kTileNodes];
          if constexpr (D == 2) {
            for (int l0 = lo[0]; l0 < hi[0]; ++l0)
              for (int l1 = lo[1]; l1 < hi[1]; ++l1) {
                const int a = (l0 + 1 + kBlock * off[0]) * kTile + l1 + 1 + kBlock * off[1];
                acc[l0 * kBlock + l1] += ConstLaneMap(tile + a * kLanes);
              }
          } else {
            for (int l0 = lo[0]; l0 < hi[0]; ++l0)
              for (int l1 = lo[1]; l1 < hi[1]; ++l1)
                for (int l2 = lo[2]; l2 < hi[2]; ++l2) {
                  const int a = ((l0 + 1 + kBlock * off[0]) * kTile + l1 + 1 + kBlock * off[1]) * kTile + l2 + 1 +
                                kBlock * off[2];
                  acc[(l0 * kBlock + l1) * kBlock + l2] += ConstLaneMap(tile + a * kLanes);
                }
          }
        }
        int blk[D];
        unpack_key<D>(gkeys_[g], blk);
        const size_t base = static_cast<size_t>(g) * kNodes;
        // Debris boxes that can reach this block's nodes.
        bool near_debris = false;
        if (debris_) {
          double centre[3] = {0, 0, 0}, half_diag2 = 0;
          for (int d = 0; d < D; ++d) {
            centre[d] = grid_lo_[d] + (blk[d] * kBlock + 0.5 * (kBlock - 1)) * dx_;
            half_diag2 += 0.25 * ((kBlock - 1) * dx_) * ((kBlock - 1) * dx_);
          }
          const auto& views = debris_->views();
          for (int b = 0; b < int(views.size()) && !near_debris; ++b) {
            double r2 = 0;
            for (int d = 0; d < 3; ++d) r2 += (centre[d] - views[b].centre[d]) * (centre[d] - views[b].centre[d]);
            const double reach = std::sqrt(half_diag2) + debris_->bounding_radius(b) + dx_;
            near_debris = r2 <= reach * reach;
          }
        }
        const int slot = has_sym_ ? zone_.slot(g) : -1;
        for (int k = 0; k < kNodes; ++k) {
          int node[D];
          for (int d = D - 1, r = k; d >= 0; --d, r /= kBlock) node[d] = blk[d] * kBlock + r % kBlock;
          if (slot >= 0 && in_symmetry_zone(node[sym_.axis])) {  // folded across the plane first, updated after
            sym_acc_[static_cast<size_t>(slot) * kNodes + k] = acc[k];
            continue;
          }
          update_node(acc[k], g, base + k, node, near_debris, 1.0, dt, inv_cell_volume, my_impulse, my_coupling, my_ghosts);
        }
      }
      if (has_sym_) {
        // After the barrier every raw node near the plane is stored. The nodes on the modelled side and on the
        // plane take their fold (what the whole would give them) and are updated; a load on the plane is half
        // the whole's. Each reads its own entry and its mirror's beyond the plane, which nobody writes.
        Lane sign;
        for (int c = 0; c < kLanes; ++c) sign[c] = T(mpm::symmetry_channel_sign(sym_, c));
        const long nq = static_cast<long>(zone_.entries());
#pragma omp for schedule(static)
        for (long q = 0; q < nq; ++q) {
          int node[D];
          const long g = zone_.node(q, gkeys_, node);
          const int k = static_cast<int>(q % kNodes);
          if (!in_symmetry_zone(node[sym_.axis])) continue;  // updated in the loop above
          const int side = mpm::symmetry_side(sym_, node[sym_.axis]);
          if (side > 0) continue;  // beyond: mirrored after the walls (mirror_beyond_symmetry)
          Lane a = sym_acc_[q];
          if (side == 0) {
            a += sign * a;
          } else {
            const long m = zone_.mirror_entry(node, gkeys_);
            if (m >= 0) a += sign * sym_acc_[m];
          }
          // No debris near: a scene with a symmetry plane has none (setup_boundaries).
          update_node(a, g, static_cast<size_t>(g) * kNodes + k, node, false, side == 0 ? 0.5 : 1.0, dt,
                      inv_cell_volume, my_impulse, my_coupling, my_ghosts);
        }
      }
    }
    std::fill(load_impulse_.begin(), load_impulse_.end(), 0.0);
    for (int t = 0; t < nthreads; ++t)
      for (size_t k = 0; k < load_impulse_.size(); ++k) load_impulse_[k] += impulse[t * load_impulse_.size() + k];
    reflect_ghosts();
    if (has_sym_) mirror_beyond_symmetry();
    if (debris_) couple_debris(double(dt));
  }

  bool in_symmetry_zone(int i) const { return zone_.in_zone(i); }
  void index_symmetry_blocks() {
    zone_.index(gkeys_);
    sym_acc_.resize(zone_.entries());
  }
  // After the walls and the ghosts: every node beyond the plane is the reflection of its mirror; one whose
  // mirror lies outside the zone (more than SymmetryZone::kZone cells beyond, no mass) is emptied.
  void mirror_beyond_symmetry() {
    const long nq = static_cast<long>(zone_.entries());
#pragma omp parallel for schedule(static)
    for (long q = 0; q < nq; ++q) {
      int node[D];
      const long g = zone_.node(q, gkeys_, node);
      const int k = static_cast<int>(q % kNodes);
      if (mpm::symmetry_side(sym_, node[sym_.axis]) <= 0) continue;
      const size_t idx = static_cast<size_t>(g) * kNodes + k;
      const long m = zone_.mirror_entry(node, gkeys_);
      if (m < 0) {  // nothing on the modelled side within reach: no water here either
        gm_[idx] = ge_[idx] = gfill_[idx] = T(0);
        gwall_[idx] = 0;
        for (int d = 0; d < D; ++d) gv_[d][idx] = T(0);
        continue;
      }
      const size_t mi = static_cast<size_t>(zone_.block(m)) * kNodes + m % kNodes;
      gm_[idx] = gm_[mi];
      ge_[idx] = ge_[mi];
      gfill_[idx] = gfill_[mi];
      gwall_[idx] = gwall_[mi];
      for (int d = 0; d < D; ++d) gv_[d][idx] = T(mpm::symmetry_channel_sign(sym_, 1 + d)) * gv_[d][mi];
    }
  }

  // Ghost nodes exchange tangential momentum with their reflection, a free node with water (mpm::ghost_exchange).
  // Every exchange is computed from the velocities the grid update left, the ghosts' changes applied at once and
  // the mirrors' summed after, in ghost-node order (the threads' lists merged and sorted), so that the result does
  // not depend on the thread count. No wall load: the exchange is internal to the water.
  void reflect_ghosts() {
    // Each thread's list is in node order already (a dynamic schedule hands a thread its chunks in increasing
    // order), so merging the lists suffices.
    all_ghosts_.clear();
    const auto by_node = [](const Ghost& a, const Ghost& b) { return a.idx < b.idx; };
    for (const auto& list : ghosts_) {
      const auto mid = static_cast<std::ptrdiff_t>(all_ghosts_.size());
      all_ghosts_.insert(all_ghosts_.end(), list.begin(), list.end());
      std::inplace_merge(all_ghosts_.begin(), all_ghosts_.begin() + mid, all_ghosts_.end(), by_node);
    }
    if (!std::is_sorted(all_ghosts_.begin(), all_ghosts_.end(), by_node))  // a schedule that does not keep the order
      std::sort(all_ghosts_.begin(), all_ghosts_.end(), by_node);
    // The exchanges in parallel (each writes its own ghost and its own entry), the mirrors' changes in order.
    const long count = static_cast<long>(all_ghosts_.size());
    mirror_dv_.resize(all_ghosts_.size());
#pragma omp parallel for schedule(static)
    for (long q = 0; q < count; ++q) {
      const Ghost& gh = all_ghosts_[q];
      MirrorChange& c = mirror_dv_[q];
      c.node = kNoMirror;
      const long gi = mpm::grid_index<D>(gkeys_, gh.offset);
      if (gi < 0) continue;
      const size_t mi = static_cast<size_t>(gi);
      if (gm_[mi] <= T(0) || gwall_[mi]) continue;
      T vg[D], vm[D], dvg[D];
      for (int d = 0; d < D; ++d) {
        vg[d] = gv_[d][gh.idx];
        vm[d] = gv_[d][mi];
      }
      mpm::ghost_exchange<D>(vg, gh.vpre, gm_[gh.idx], vm, gm_[mi], gh.axes, push_axes_, dvg, c.dv);
      for (int d = 0; d < D; ++d) gv_[d][gh.idx] += dvg[d];  // ghosts are never mirrors: no exchange reads it
      c.node = mi;
    }
    // The mirrors' changes in ghost order; the normal part of each (the image's push) is the wall's load.
    for (size_t q = 0; q < mirror_dv_.size(); ++q) {
      const MirrorChange& c = mirror_dv_[q];
      if (c.node == kNoMirror) continue;
      const Ghost& gh = all_ghosts_[q];
      for (int d = 0; d < D; ++d) {
        gv_[d][c.node] += c.dv[d];
        if (gh.wall >= 0 && (gh.axes & (1u << d)))
          load_impulse_[static_cast<size_t>(gh.wall) * D + d] -= gh.load_weight * double(gm_[c.node]) * double(c.dv[d]);
      }
    }
  }

  // Whether a debris box may come within `margin` of the block's particles (a particle may sit up to one cell
  // outside its block).
  bool block_near_debris(uint64_t key, double margin) const {
    int blk[D];
    unpack_key<D>(key, blk);
    double centre[3] = {0, 0, 0}, half_diag2 = 0;
    for (int d = 0; d < D; ++d) {
      centre[d] = grid_lo_[d] + (blk[d] * kBlock + 0.5 * kBlock) * dx_;
      half_diag2 += 0.25 * ((kBlock + 2) * dx_) * ((kBlock + 2) * dx_);
    }
    const auto& views = debris_->views();
    for (int b = 0; b < int(views.size()); ++b) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (centre[d] - views[b].centre[d]) * (centre[d] - views[b].centre[d]);
      const double reach = std::sqrt(half_diag2) + debris_->bounding_radius(b) + margin;
      if (r2 <= reach * reach) return true;
    }
    return false;
  }

  // A particle inside a box goes back to its surface, without the velocity that approached it; the momentum
  // it loses is added to acc[body] (impulse, then moment about the origin) for the box (debris_coupling.h).
  void push_out_of_debris(size_t i, double* acc) {
    double x[3] = {0, 0, 0}, v[3] = {0, 0, 0}, share[6];
    for (int d = 0; d < D; ++d) {
      x[d] = x_[d][i];
      v[d] = v_[d][i];
    }
    const auto& views = debris_->views();
    const int b = mpm::push_out_of_box(views.data(), debris_->bounding_radii().data(), int(views.size()),
                                       rho_ * double(vol_[i]), x, v, share);
    if (b < 0) return;
    for (int d = 0; d < D; ++d) {
      x_[d][i] = T(x[d]);
      v_[d][i] = T(v[d]);
    }
    for (int k = 0; k < 6; ++k) acc[b * 6 + k] += share[k];
  }

  // The debris exchange: the nodes in boxes, in grid order (so the sums do not depend on the thread count),
  // solved together with the boxes' motion; then the boxes step by dt.
  void couple_debris(double dt) {
    std::vector<CouplingNode> nodes;
    for (auto& part : coupling_) nodes.insert(nodes.end(), part.begin(), part.end());
    std::sort(nodes.begin(), nodes.end(), [](const CouplingNode& a, const CouplingNode& b) { return a.id < b.id; });
    debris_->exchange(nodes, dt);
    for (const auto& c : nodes)
      for (int d = 0; d < D; ++d) gv_[d][c.id] = T(c.v[d]);
  }

  // G2P: new velocity, affine matrix, J (with J-bar mixing) and position; checks for blow-up.
  void g2p(T dt) {
    const T dx = T(dx_);
    const T cscale = T(4) * inv_dx_ * inv_dx_;
    const T fill_rate = T(mpm::fill_rate(double(dt), c_, dx_));
    // Locals of the members the particle loop reads: its stores to the particle arrays could alias a member
    // of type T, which the compiler would then reload (and the Tait law's set-up redo) for every particle.
    const mpm::TaitLaw<T> law = law_;
    const T inv_dx = inv_dx_;
    mpm::G2pConstants<D, T> g2p_k;
    g2p_k.dt = dt;
    g2p_k.psi = psi_;
    g2p_k.fill_rate = fill_rate;
    g2p_k.fill_tol = fill_tolerance_;
    g2p_k.law_d = law_d_;
    g2p_k.has_sym = has_sym_;
    g2p_k.sym = sym_;
    T lo_grid[D], grav[D];
    for (int d = 0; d < D; ++d) {
      g2p_k.slope[d] = strain_slope_[d];
      lo_grid[d] = T(grid_lo_[d]);
      grav[d] = gravity_[d];
    }
    const double rho = rho_;
    const long nblocks = static_cast<long>(pkeys_.size());
    double vmax2 = 0, ke = 0, pe = 0, el = 0, fill_work = 0;
    long bad = std::numeric_limits<long>::max();
    int bad_kind = 0;
    bool resort = false;
    double lo_ok[D], hi_ok[D];
    for (int d = 0; d < D; ++d) {
      lo_ok[d] = scene_.domain_lo[d] - dx_;
      hi_ok[d] = scene_.domain_hi[d] + dx_;
    }
    const int nbodies = debris_ ? debris_->body_count() : 0;
    // Only the blocks near a box can push particles out: they zero their own slots in the loop and are flagged,
    // and only they are summed after it (a block far from every box would add exact zeros), instead of zeroing
    // and summing every block's slots serially each step.
    if (debris_) {
      push_out_.resize(static_cast<size_t>(nblocks) * nbodies * 6);
      push_near_.assign(static_cast<size_t>(nblocks), 0);
    }
    static const std::vector<TileNode> tile_map = mpm::make_tile_map<D>();
#pragma omp parallel for schedule(dynamic, 4) reduction(max : vmax2) reduction(+ : ke, pe, el, fill_work) reduction(|| : resort)
    for (long p = 0; p < nblocks; ++p) {
      const bool near_debris = debris_ && block_near_debris(pkeys_[p], 2 * dx_);
      if (near_debris) {
        push_near_[p] = 1;
        std::fill_n(&push_out_[static_cast<size_t>(p) * nbodies * 6], nbodies * 6, 0.0);
      }
      T vmax2_b = 0, ke_b = 0, pe_b = 0, el_b = 0;
      // Gather the tile around this block: per node the velocity, then (free nodes only) strain, fill and weight.
      alignas(64) T tg[kTileNodes * kLanes];
      int blk[D], origin[D];
      unpack_key<D>(pkeys_[p], blk);
      for (int d = 0; d < D; ++d) origin[d] = blk[d] * kBlock - 1;
      // Only the tile box P2G found (the particles have not moved since): the rest of tg is never read.
      const auto fetch = [&](int a) {
        const int32_t g = p_nbr_[p * kNbr + tile_map[a].block];
        const size_t idx = static_cast<size_t>(g) * kNodes + tile_map[a].local;
        T* t = tg + a * kLanes;
        for (int d = 0; d < D; ++d) t[d] = gv_[d][idx];
        const T free = gwall_[idx] ? T(0) : T(1);
        t[D] = free * ge_[idx];
        t[D + 1] = free * gfill_[idx];
        t[D + 2] = free;
        for (int c = D + 3; c < kLanes; ++c) t[c] = T(0);
      };
      mpm::for_each_box_row<D>(tile_box_[p], [&](int a, int len) {
        for (int k = 0; k < len; ++k) fetch(a + k);
      });
      // The stencil weights of a batch of particles first, in a loop of their own; then the gather and update
      // one particle at a time.
      for (uint32_t b0 = pstart_[p]; b0 < pstart_[p + 1]; b0 += kBatch) {
        const int nb = static_cast<int>(std::min<uint32_t>(kBatch, pstart_[p + 1] - b0));
        alignas(64) T bw[D][3][kBatch], bf[D][kBatch];
        alignas(64) int brel[D][kBatch];
        for (int d = 0; d < D; ++d) {
          const T* xd = x_[d].data() + b0;
          for (int j = 0; j < nb; ++j) {
            T fj, w[3];
            brel[d][j] = mpm::stencil_base((xd[j] - lo_grid[d]) * inv_dx, fj) - origin[d];
            mpm::bspline_weights(fj, w);
            bf[d][j] = fj;
            for (int c = 0; c < 3; ++c) bw[d][c][j] = w[c];
          }
        }
      for (int j = 0; j < nb; ++j) {
        const uint32_t i = b0 + j;
        T w[D][3], f[D];
        int rel[D];
        for (int d = 0; d < D; ++d) {
          rel[d] = brel[d][j];
          f[d] = bf[d][j];
          for (int c = 0; c < 3; ++c) w[d][c] = bw[d][c][j];
        }
        // Separable sums over the stencil: S = sum w n, and M[b] = sum w i_b n (i_b the node's offset 0, 1, 2
        // on axis b), n the node's lanes. Then v = S[0..D), the APIC matrix C_ab = sum w v_a (i_b - f_b) dx
        // = (M[b][a] - f_b S[a]) dx, and the free-node sums of strain, fill and weight are S[D..D+3).
        Lane S = Lane::Zero(), M[D];
        for (int b = 0; b < D; ++b) M[b] = Lane::Zero();
        if constexpr (D == 2) {
          for (int i0 = 0; i0 < 3; ++i0) {
            const T* n = tg + ((rel[0] + i0) * kTile + rel[1]) * kLanes;
            const Lane n1 = ConstLaneMap(n + kLanes), n2 = ConstLaneMap(n + 2 * kLanes);
            const Lane r = w[1][0] * ConstLaneMap(n) + w[1][1] * n1 + w[1][2] * n2;
            const Lane r1 = w[1][1] * n1 + (T(2) * w[1][2]) * n2;
            S += w[0][i0] * r;
            M[0] += (T(i0) * w[0][i0]) * r;
            M[1] += w[0][i0] * r1;
          }
        } else {
          for (int i0 = 0; i0 < 3; ++i0) {
            Lane S1 = Lane::Zero(), M1 = Lane::Zero(), M2 = Lane::Zero();
            for (int i1 = 0; i1 < 3; ++i1) {
              const T* n = tg + (((rel[0] + i0) * kTile + rel[1] + i1) * kTile + rel[2]) * kLanes;
              const Lane n1 = ConstLaneMap(n + kLanes), n2 = ConstLaneMap(n + 2 * kLanes);
              const Lane r = w[2][0] * ConstLaneMap(n) + w[2][1] * n1 + w[2][2] * n2;
              const Lane r2 = w[2][1] * n1 + (T(2) * w[2][2]) * n2;
              S1 += w[1][i1] * r;
              M1 += (T(i1) * w[1][i1]) * r;
              M2 += w[1][i1] * r2;
            }
            S += w[0][i0] * S1;
            M[0] += (T(i0) * w[0][i0]) * S1;
            M[1] += w[0][i0] * M1;
            M[2] += w[0][i0] * M2;
          }
        }
        T vn[D], Cn[D * D];
        for (int a = 0; a < D; ++a) {
          vn[a] = S[a];
          for (int b = 0; b < D; ++b) Cn[a * D + b] = (M[b][a] - f[b] * S[a]) * dx;
        }
        const T Jg = S[D], Fg = S[D + 1], wsum = S[D + 2];
        for (int k = 0; k < D * D; ++k) Cn[k] *= cscale;
        T xp[D];
        for (int d = 0; d < D; ++d) xp[d] = x_[d][i];
        T e = e_[i];
        fill_work += mpm::g2p_particle<D>(g2p_k, Jg, Fg, wsum, vol_[i], e, xp, vn, Cn);
        e_[i] = e;
        T v2 = 0, gx = 0;
        bool finite = std::isfinite(e) && e > T(-1);
        bool inside = true;
        for (int d = 0; d < D; ++d) {
          v_[d][i] = vn[d];
          x_[d][i] = xp[d];
        }
        if (near_debris) push_out_of_debris(i, &push_out_[static_cast<size_t>(p) * nbodies * 6]);
        for (int d = 0; d < D; ++d) {
          const T xn = x_[d][i], vd = v_[d][i];
          finite &= std::isfinite(xn) && std::isfinite(vd);
          inside &= xn >= T(lo_ok[d]) && xn <= T(hi_ok[d]);
          v2 += vd * vd;
          gx += grav[d] * xn;
        }
        for (int k = 0; k < D * D; ++k) C_[k][i] = Cn[k];
        if (!finite || !inside) {
#pragma omp critical(flume_bad_particle)
          if (static_cast<long>(i) < bad) {
            bad = static_cast<long>(i);
            bad_kind = finite ? 2 : 1;
          }
          continue;
        }
        // The audit's sums, per block in T (the audit's slack is 1 % of the energy scale; a float block sum is
        // good to 1e-6 of it) and then in double across blocks.
        const T V = vol_[i];
        vmax2_b = std::max(vmax2_b, v2);
        ke_b += V * v2;
        pe_b -= V * gx;
        el_b += V * law.energy_density(e);
      }
      }
      {  // a particle drifted out of the tile margin: re-sort before the next scatter
        const T* xs[D];
        for (int d = 0; d < D; ++d) xs[d] = x_[d].data();
        int lo[D], hi[D];
        mpm::stencil_base_range<D>(xs, pstart_[p], pstart_[p + 1], lo_grid, inv_dx, lo, hi);
        for (int d = 0; d < D; ++d) resort |= lo[d] - origin[d] < 0 || hi[d] - origin[d] > kBlock + 1;
      }
      vmax2 = std::max(vmax2, double(vmax2_b));
      ke += 0.5 * rho * double(ke_b);
      pe += rho * double(pe_b);
      el += double(el_b);
    }
    if (debris_)  // the particles' lost momentum goes to the boxes, summed in block order (thread-independent)
      for (int b = 0; b < nbodies; ++b) {
        double J[3] = {0, 0, 0}, L[3] = {0, 0, 0};
        for (long p = 0; p < nblocks; ++p) {
          if (!push_near_[p]) continue;
          for (int d = 0; d < 3; ++d) {
            J[d] += push_out_[(static_cast<size_t>(p) * nbodies + b) * 6 + d];
            L[d] += push_out_[(static_cast<size_t>(p) * nbodies + b) * 6 + 3 + d];
          }
        }
        debris_->add_particle_impulse(b, J, L);
      }
    max_speed_ = std::sqrt(vmax2);
    needs_sort_ = resort;
    // The volume constraint (mpm::fill_correction) does work on the water that the audit cannot otherwise
    // see: it restores the elastic energy of water that crowded without compressing. What it adds is counted
    // as supplied energy; what it removes (lowering J of water in tension) is dissipation and is not
    // (crediting it hid an energy rise at a dam-break front: docs/solver.md).
    energy0_ += fill_work;
    const double t_new = time_ + double(dt);
    if (bad != std::numeric_limits<long>::max()) {
      double xp[D];
      for (int d = 0; d < D; ++d) xp[d] = x_[d][bad];
      fail(mpm::bad_particle_message(bad_kind, t_new, steps_ + 1, double(dt), bad, xp, D));
      return;
    }
    const double e_debris = debris_ ? debris_->energy() : 0.0;
    const double e = ke + pe + el + e_debris;
    if (e > energy0_ + energy_slack_)
      fail(mpm::energy_growth_message<D>(t_new, steps_ + 1, e, energy0_, max_speed_, x_, v_, n_));
    last_energy_ = {ke, pe, el, e_debris};
  }

  ParticleArrays<D, T> particle_arrays() {
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
  // The inflow moves, adds and removes particles after the step; the energy audit is told what it did.
  void apply_inflow(double t0, double t1) {
    const auto change = inflow_->apply(t0, t1);
    energy0_ += change.energy;
    n_ = x_[0].size();
    if (change.structural) mass_ = water_mass(vol_, rho_);
    needs_sort_ = needs_sort_ || change.structural;
  }

  void fail(const std::string& what) {
    status_ = RunStatus::kUnstable;
    message_ = what;
  }

 public:
  const Energy& last_energy() const { return last_energy_; }
  const Scene& scene() const { return scene_; }

 private:
  Scene scene_;
  InstrumentSet<MpmSolver> instruments_;
  double dx_ = 0;
  T inv_dx_ = 0;
  double grid_lo_[D] = {};
  T gravity_[D] = {};
  T mu_ = 0, psi_ = 0;
  mpm::TaitLaw<T> law_;         // the particle loops copy it into a local: a member is reloaded after every store
  mpm::TaitLaw<double> law_d_;  // the same law in double, for the energy audit and diagnostics
  T fill_tolerance_ = 0;  // mpm::fill_correction
  T strain_slope_[D] = {};  // s of mpm::hydrostatic_strain
  double c_ = 0;
  double spacing_ = 0, rho_ = 0, mass_ = 0;  // mass_: rho times the particles' volumes summed in double
  size_t n_ = 0;
  std::vector<T> held_;  // 1 for water the reservoir's vacuum holds (empty when nothing is held)
  std::vector<T> x_[D], v_[D], C_[D * D], e_;  // e: volumetric strain J - 1
  std::vector<T> vol_;  // reference volume (solver/seeding.h): the particle's mass is rho vol
  std::vector<uint64_t> pkeys_, gkeys_;
  std::vector<uint32_t> pstart_;
  std::vector<int32_t> p_nbr_, g_nbr_;
  std::vector<uint32_t> g_bnd_start_;
  std::vector<int32_t> g_bnd_;
  std::vector<TileBox> tile_box_;  // per particle block, from P2G; read by the grid gather and by G2P
  std::vector<T> gm_, gv_[D], ge_, gfill_, tiles_;  // gfill: particle volume per cell volume at a node
  std::vector<uint8_t> gwall_;  // 1 where a wall set the node's velocity
  std::vector<uint64_t> sort_key_, sort_key_scratch_;  // sort_particles' work arrays, kept to avoid page faults
  std::vector<uint32_t> sort_order_;
  BlockSortWork sort_work_;
  std::vector<T> sort_scratch_;
  std::vector<Wall> walls_;
  mpm::Container<D, T> container_;  // the domain box
  double subcell_rate0_ = 0;        // mpm::subcell_drag's rate
  std::vector<double> load_impulse_;
  std::unique_ptr<DebrisCoupling> debris_;
  std::unique_ptr<InflowBoundary<D, T>> inflow_;
  std::vector<T> tag_;  // the inflow's buffer particles (1) and free water (0); empty without an inflow
  std::vector<std::vector<Ghost>> ghosts_;  // per thread: this step's ghost nodes (reflect_ghosts)
  std::vector<Ghost> all_ghosts_;            // all of them, in node order
  mpm::SymmetryZone<D> zone_;  // the nodes near the symmetry plane, stored raw and updated after the fold
  std::vector<Lane> sym_acc_;  // per zone entry: this step's raw lanes
  bool has_sym_ = false;
  mpm::SymmetryPlane sym_;
  struct MirrorChange {
    size_t node;
    T dv[D];
  };
  static constexpr size_t kNoMirror = ~size_t(0);
  std::vector<MirrorChange> mirror_dv_;  // the mirrors' velocity changes, applied after every exchange
  unsigned push_axes_ = 0;               // the wall normals that push with a ghost's image (mpm::image_push_axes)
  std::vector<std::vector<CouplingNode>> coupling_;  // per thread: the nodes found in boxes this step
  std::vector<double> push_out_;  // per particle block and box: impulse and moment of pushed-out particles
  std::vector<uint8_t> push_near_;  // per particle block: whether it is near a box (its push_out_ slots are set)
  // Nodes up to one cell outside a box are its moving-wall nodes: then a water particle touching the box puts
  // (nearly) all its weight on them (quadratic B-splines reach 1.5 cells; nodes 1-1.5 cells away carry at
  // most 1/8), so the box feels the water's full pressure. With only the nodes inside the box, the share is
  // that of the face's position between nodes, 1/2 on average, and a floating box sat too deep
  // (docs/solver.md; tests/solver/test_debris.cpp).
  static constexpr double coupling_band_ = 1.0;
  bool needs_sort_ = true;
  enum Stage { kStageSort, kStageP2g, kStageGrid, kStageG2p, kStageOther, kStages };
  double stage_s_[kStages] = {};  // wall seconds per stage of the steps so far (stage_seconds)
  double time_ = 0, dt_ = 0, max_speed_ = 0;
  long steps_ = 0;
  double energy0_ = 0, energy_slack_ = 0;
  Energy last_energy_;
  RunStatus status_ = RunStatus::kRunning;
  std::string message_;
};

}  // namespace
}  // namespace mpm

using mpm::MpmSolver;

std::unique_ptr<Simulation> make_cpu_simulation(const Scene& scene, const SimulationOptions& options) {
  const bool f = scene.solver.precision == Precision::kFloat;
  if (scene.dimension == 2) {
    if (f) return std::make_unique<MpmSolver<2, float>>(scene, options);
    return std::make_unique<MpmSolver<2, double>>(scene, options);
  }
  if (f) return std::make_unique<MpmSolver<3, float>>(scene, options);
  return std::make_unique<MpmSolver<3, double>>(scene, options);
}

}  // namespace flume
