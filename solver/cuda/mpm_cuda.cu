// The CUDA backend of the MLS-MPM solver: the same step as the CPU backend (solver/mpm/cpu_solver.h), with
// the physics taken from the same inline functions (solver/mpm_kernels.h, solver/mpm/*_k.h: one particle's
// P2G terms and G2P update, one node against the boundaries, block keys), launched by mpm::parallel_for
// (solver/mpm/launch.h), on device arrays. This file holds the stencil loops with their atomics, the launches
// and the memory.
//
// Inflow and checkpoints go through the host: the inflow boundary (solver/inflow.h) works on host arrays, so
// the particles are copied down and back around it each step; a checkpoint copies the particles and their
// sort keys.
//
// Debris. The rigid bodies stay on the host (DebrisCoupling, Bullet contact). Each step the device finds the
// nodes in the boxes' bands and the particles inside a box (mpm/debris_k.h, the CPU's bodies), compacts them
// in storage order and copies only those down: the host solves the exchange and steps the boxes, and the
// projected node velocities go back up. Storage order is the CPU's grid order, so the sums are the CPU's.
//
// Layout. Particles are structure-of-arrays device vectors, sorted by the grid block (kBlock^D nodes) that
// holds their stencil's base node, exactly as on the CPU. The grid is block-sparse: after each sort the
// blocks are rebuilt on the device (radix sort of the particle blocks' 3^D neighbour keys, unique), and each
// particle block gets a table of its 3^D neighbours' grid block indices. Grid arrays are channel-major
// (mass, momentum/velocity x D, mass-weighted strain), so memory follows the water as on the CPU. The re-sort
// criterion is the CPU's: a particle's base node drifting more than one cell out of its sorted block.
//
// Scatter and gather. P2G and G2P run a thread block per particle block (mpm::tiled_for) on a tile, in shared
// memory, of the nodes the block's stencils reach: P2G's threads add their particles into it with shared
// atomics and each tile node then goes to the grid with one global atomic per channel; G2P reads the tile
// from the grid once and its particles gather from it (global atomics and gathers bound the
// one-thread-per-particle stages: docs/benchmarks.md). The scatter's order is not fixed: results agree with
// the CPU, and between GPU runs, to round-off.
//
// Instruments. The CPU's InstrumentSet is reused unchanged. Velocity probes and volume gauges are sums over
// the particles of one term each (solver/particle_sums.h), reduced here on the device (sum_particles): a few
// numbers come back (pressure probes too, for their first sample at t = 0). Connected gauges and sections
// read particle positions and velocities from host mirrors, copied lazily, only on a step where one of them
// samples (2 D arrays of n values: 24 MB for a million particles in 3D float, about 1-2 ms over PCIe);
// sections also read the reference volumes, copied only after a sort has moved them. Diagnostics use the
// energies reduced on the device during G2P: no copy. Load cells sum the wall impulse on the device (atomics
// into D doubles per wall), copied back each step (a few bytes) only when the scene has load cells; pressure
// probes likewise sum the walls' push at the nodes near them (mpm::add_probe_push, one double per probe),
// read after every step.
//
// The code uses Thrust only (device_vector, sort, unique, lower_bound, for_each, transform_reduce) with
// functor structs, so that the same file also compiles with the host compiler against Thrust's sequential
// C++ system (FLUME_CUDA_EMULATION, see mpm_cuda_emulated.cpp): the tests run every index computation and
// formula here on the CPU even on a machine without a GPU.
#include <thrust/binary_search.h>
#include <thrust/copy.h>
#include <thrust/device_vector.h>
#include <thrust/execution_policy.h>
#include <thrust/fill.h>
#include <thrust/for_each.h>
#include <thrust/gather.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/sequence.h>
#include <thrust/sort.h>
#include <thrust/transform_reduce.h>
#include <thrust/unique.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <memory>
#include <sstream>
#include <vector>

#ifndef FLUME_CUDA_EMULATION
#include <cuda_runtime.h>
#endif

#include "solver/interleave_axes.h"
#include "solver/checkpoint.h"
#include "solver/debris_coupling.h"
#include "solver/cuda/mpm_cuda.h"
#include "solver/inflow.h"
#include "solver/instruments.h"
#include "solver/mpm/audit.h"
#include "solver/mpm/blocks_k.h"
#include "solver/mpm/boundaries.h"
#include "solver/mpm/constants.h"
#include "solver/mpm/debris_k.h"
#include "solver/mpm/diagnostics_k.h"
#include "solver/mpm/launch.h"
#include "solver/mpm/node_k.h"
#include "solver/mpm/particle_k.h"
#include "solver/mpm/run_state.h"
#include "solver/mpm_kernels.h"
#include "solver/particle_sums.h"
#include "solver/seeding.h"
#include "solver/simulation.h"
#include "solver/symmetry.h"

namespace flume {
namespace mpm {
namespace {

namespace thr = THRUST_NS_QUALIFIER;
using mpm::kBlock;


FLUME_HD bool is_finite(double v) {
#if defined(__CUDA_ARCH__)
  return isfinite(v);
#else
  return std::isfinite(v);
#endif
}

using mpm::pack_key;
using mpm::unpack_key;

template <int D, typename T>
using Wall = mpm::Wall<D, T>;

// Everything the kernels read, by value: raw device pointers and the scene's constants.
template <int D, typename T>
struct View {
  static constexpr int kNodes = mpm::Pow<D>::of(kBlock);
  static constexpr int kNbr = mpm::Pow<D>::of(3);
  static constexpr int kChannels = D + 3;  // mass, momentum (D), mass-weighted strain J - 1, particle volume
  // With FLIP (solver.flip) also the transfer's momentum (D, mpm::p2g_transfer_momentum), divided by the mass
  // in the update: the grid's old velocity.
  static constexpr int kMaxChannels = 2 * D + 3;

  // particles
  T* x[D];
  T* v[D];
  T* C[D * D];
  T* e;
  const T* vol;   // reference volume (solver/seeding.h): the particle's mass is rho vol
  const T* held;  // 1 for water the reservoir's vacuum holds; null when nothing is held
  double* fill_work;  // per particle: the elastic energy the volume constraint added this step (J)
  const int32_t* pblk;  // index of the particle's (sorted) block in pkeys
  // blocks and grid
  const uint64_t* pkeys;
  const int32_t* p_nbr;  // kNbr grid block indices per particle block
  const uint64_t* gkeys;
  T* grid;  // channels x nodes, channel-major
  int channels;  // kChannels, or kMaxChannels with FLIP
  T flip;        // mpm::flip_velocity's alpha for this step (mpm::flip_for_step)
  uint8_t* gwall;  // per node: the axes its walls hold (mpm::apply_boundaries), all of them on a moving box
  int64_t* ghost_mirror;  // per node: its reflection's grid index (mpm::ghost_half_space), or -1
  uint8_t* ghost_axes;    // per node: the normal axes the reflection keeps
  T* ghost_dv;            // D x nodes: a ghost's velocity before the walls, then its group's (GhostExchange)
  T* ghost_pool;          // kGhostPoolLanes D x nodes: a mirror's sums over its ghosts (mpm::ghost_pool_terms)
  int32_t* ghost_wall;    // per node: the scene wall whose load takes the image's push, or -1
  unsigned push_axes;     // mpm::image_push_axes
  double subcell_rate = 0;  // mpm::subcell_drag's rate0: the sound speed over a cell
  int has_sym = 0;        // a symmetry plane (mpm::SymmetryPlane): folded before the update, mirrored after
  mpm::SymmetryPlane sym;
  size_t nodes;
  // constants
  T dx, inv_dx, rho, mu, psi, fill_tol, inv_cell_volume;
  mpm::TaitLaw<T> law;
  mpm::TaitLaw<double> law_d;  // the energy audit's, in double
  double rho_d;
  T grid_lo[D], gravity[D], strain_slope[D];
  double dx_d, grid_lo_d[D];
  const Wall<D, T>* walls;
  int n_walls;
  mpm::Container<D, T> container;  // the domain box
  double* impulse;  // walls x D, or null when no load cell reads it
  mpm::ProbeFaces probes;  // the pressure probes' faces (device arrays), count 0 when there are none
  double* probe_push;      // per probe: this step's push (mpm::add_probe_push)

  // Global node coordinates of grid index idx.
  FLUME_HD void node_of(size_t idx, int* node) const {
    int blk[D];
    unpack_key<D>(gkeys[idx / kNodes], blk);
    for (int d = D - 1, r = static_cast<int>(idx % kNodes); d >= 0; --d, r /= kBlock)
      node[d] = blk[d] * kBlock + r % kBlock;
  }

  // Where node idx lies against the symmetry plane (`side`: mpm::symmetry_side) and, beyond it, the grid index
  // of its mirror (-1 where no block holds it, or not beyond).
  FLUME_HD int64_t symmetry_mirror(size_t idx, int& side) const;

  // Grid index of node `node` (global node coordinates) by a binary search of the sorted grid blocks; -1 where
  // no block holds it.
  FLUME_HD int64_t grid_index(const int* node) const {
    return mpm::node_index<D>(gkeys, nodes / kNodes, node);
  }

  // Grid index of node `node` (global node coordinates) seen from particle block `pb`: the node lies in one
  // of the block's 3^D neighbours because a particle is re-sorted before its stencil leaves them.
  FLUME_HD size_t node_index(int32_t pb, const int* blk, const int* node) const {
    int o = 0, local = 0;
    for (int d = 0; d < D; ++d) {
      const int bo = node[d] / kBlock - blk[d];  // -1, 0 or +1; node >= 0 thanks to the padding
      o = o * 3 + bo + 1;
      local = local * kBlock + node[d] - (blk[d] + bo) * kBlock;
    }
    return static_cast<size_t>(p_nbr[static_cast<size_t>(pb) * kNbr + o]) * kNodes + local;
  }
};

template <int D, typename T>
struct SortKey {
  View<D, T> s;
  uint64_t* key;
  FLUME_HD void operator()(size_t i) const {
    T xg[D];
    for (int d = 0; d < D; ++d) xg[d] = (s.x[d][i] - s.grid_lo[d]) * s.inv_dx;
    key[i] = mpm::particle_block_key<D>(xg);
  }
};

// The 3^D neighbour keys of every particle block (offsets -1, 0, +1 per axis, last axis fastest).
template <int D>
struct NeighbourKey {
  const uint64_t* pkeys;
  uint64_t* out;
  FLUME_HD void operator()(size_t j) const {
    constexpr int kNbr = mpm::Pow<D>::of(3);
    int b[D];
    unpack_key<D>(pkeys[j / kNbr], b);
    int nb[D];
    mpm::neighbour_block<D>(b, static_cast<int>(j % kNbr), nb);
    out[j] = pack_key<D>(nb);
  }
};

// P2G, one particle: mass, momentum with the MLS-MPM stress term (Hu et al. 2018, eq. 29) and the
// mass-weighted strain, less its hydrostatic part (mpm::hydrostatic_strain), handed to a scatter (P2GTiled).
template <int D, typename T>
struct P2G {
  View<D, T> s;
  T dt;
  T lift;  // the vacuum's hold on a held particle this step, per unit mass: dt f(t) |g| (upward velocity)
  // Particle i's contributions to its 3^D nodes: put(node, values) with the node's global coordinates and its
  // kChannels values (mass, momentum, mass-weighted strain, volume).
  template <typename Put>
  FLUME_HD void scatter(size_t i, const Put& put) const {
    const T dx = s.dx, V = s.vol[i], m = s.rho * V;
    const T stress_scale = -dt * T(4) * s.inv_dx * s.inv_dx;  // times the particle's reference volume
    int base[D];
    T w[D][3], f[D];
    for (int d = 0; d < D; ++d) {
      const T xg = (s.x[d][i] - s.grid_lo[d]) * s.inv_dx;
      base[d] = mpm::stencil_base(xg, f[d]);
      mpm::bspline_weights(f[d], w[d]);
    }
    T Cp[D * D], vp[D], xp[D], A[D * D], mom0[D], mJ, vol;
    for (int k = 0; k < D * D; ++k) Cp[k] = s.C[k][i];
    for (int a = 0; a < D; ++a) {
      vp[a] = s.v[a][i];
      xp[a] = s.x[a][i];
    }
    mpm::p2g_particle<D>(s.law.pressure(s.e[i]), Cp, s.e[i], V, m, vp, f, xp, dx, s.mu, stress_scale,
                         s.strain_slope, A, mom0, mJ, vol);
    const bool flip = s.channels > View<D, T>::kChannels;
    T tmom0[D] = {};
    if (flip) mpm::p2g_transfer_momentum<D>(m, vp, Cp, f, dx, tmom0);
    if (s.held) mom0[D - 1] += s.held[i] * lift * m;
    constexpr int kStencil = mpm::Pow<D>::of(3);
    for (int q = 0; q < kStencil; ++q) {
      int off[D], node[D];
      for (int d = D - 1, r = q; d >= 0; --d, r /= 3) off[d] = r % 3;
      T wt = w[0][off[0]];
      for (int d = 1; d < D; ++d) wt *= w[d][off[d]];
      for (int d = 0; d < D; ++d) node[d] = base[d] + off[d];
      T val[View<D, T>::kMaxChannels];
      val[0] = wt * m;
      for (int a = 0; a < D; ++a) {
        T mom = mom0[a];
        for (int b = 0; b < D; ++b) mom += A[a * D + b] * (T(off[b]) * dx);
        val[1 + a] = wt * mom;
      }
      val[1 + D] = wt * mJ;
      val[2 + D] = wt * vol;
      if (flip)
        for (int a = 0; a < D; ++a) {
          T mom = tmom0[a];
          for (int b = 0; b < D; ++b) mom += m * Cp[a * D + b] * (T(off[b]) * dx);
          val[D + 3 + a] = wt * mom;
        }
      put(node, val);
    }
  }
};

// The tile of a particle block for mpm::tiled_for: the nodes its particles' stencils reach. A particle's stencil
// base lies within one node of its block (re-sorted otherwise: AuditParticle), so the tile spans kBlock + 4
// nodes per axis from one node below the block. Entry v of the tile is its node's offset from that corner.
template <int D>
struct BlockTile {
  static constexpr int kSpan = kBlock + 4;
  static constexpr int kEntries = mpm::Pow<D>::of(kSpan);
  const uint64_t* pkeys;
  const int32_t* pstart;  // first particle of each particle block, and the count at the end
  FLUME_HD int tile_entries() const { return kEntries; }
  FLUME_HD void items(size_t g, size_t& first, size_t& last) const {
    first = static_cast<size_t>(pstart[g]);
    last = static_cast<size_t>(pstart[g + 1]);
  }
  // Block g's coordinates and its tile's lowest node.
  FLUME_HD void corner(size_t g, int* blk, int* lo) const {
    unpack_key<D>(pkeys[g], blk);
    for (int d = 0; d < D; ++d) lo[d] = blk[d] * kBlock - 1;
  }
  FLUME_HD static int entry(const int* node, const int* lo) {
    int v = 0;
    for (int d = 0; d < D; ++d) v = v * kSpan + node[d] - lo[d];
    return v;
  }
  FLUME_HD static void entry_node(int v, const int* lo, int* node) {
    for (int d = D - 1; d >= 0; --d, v /= kSpan) node[d] = lo[d] + v % kSpan;
  }
};

// P2G through the block's tile: its particles add into the tile, then each tile node goes to the grid once.
template <int D, typename T>
struct P2GTiled : BlockTile<D> {
  using Tile = BlockTile<D>;
  P2G<D, T> p2g;
  FLUME_HD int tile_values() const { return Tile::kEntries * p2g.s.channels; }
  FLUME_HD void load(size_t, int v, T* tile) const {
    for (int c = 0; c < p2g.s.channels; ++c) tile[c * Tile::kEntries + v] = T(0);
  }
  FLUME_HD void item(size_t g, size_t i, T* tile) const {
    int blk[D], lo[D];
    this->corner(g, blk, lo);
    p2g.scatter(i, [&](const int* node, const T* val) {
      const int v = Tile::entry(node, lo);
      for (int c = 0; c < p2g.s.channels; ++c) mpm::accumulate(&tile[c * Tile::kEntries + v], val[c]);
    });
  }
  FLUME_HD void flush(size_t g, int v, const T* tile) const {
    if (!(tile[v] != T(0))) return;  // no particle's stencil reached it (every value is then zero)
    const View<D, T>& s = p2g.s;
    int blk[D], lo[D], node[D];
    this->corner(g, blk, lo);
    Tile::entry_node(v, lo, node);
    const size_t idx = s.node_index(static_cast<int32_t>(g), blk, node);
    for (int c = 0; c < s.channels; ++c) mpm::accumulate(&s.grid[c * s.nodes + idx], tile[c * Tile::kEntries + v]);
  }
};

// The symmetry plane's fold (mpm::SymmetryPlane; MpmSolver::fold_symmetry), one node, before the update: a node
// beyond the plane adds its reflection to its mirror, a node on the plane its own. A mirror has one node beyond
// the plane, and no node both reads and is written, so no atomics are needed.
template <int D, typename T>
FLUME_HD int64_t View<D, T>::symmetry_mirror(size_t idx, int& side) const {
  int node[D];
  node_of(idx, node);
  side = mpm::symmetry_side(sym, node[sym.axis]);
  if (side <= 0) return -1;
  node[sym.axis] = sym.twice - node[sym.axis];
  return grid_index(node);
}
template <int D, typename T>
struct SymmetryFold {
  View<D, T> s;
  FLUME_HD void operator()(size_t idx) const {
    int side;
    const int64_t mi = s.symmetry_mirror(idx, side);
    if (side < 0 || !(s.grid[idx] > T(0))) return;
    if (side == 0) {
      for (int c = 0; c < s.channels; ++c)
        s.grid[c * s.nodes + idx] += T(mpm::symmetry_channel_sign<D>(s.sym, c)) * s.grid[c * s.nodes + idx];
      return;
    }
    if (mi < 0) return;
    for (int c = 0; c < s.channels; ++c)
      s.grid[c * s.nodes + mi] += T(mpm::symmetry_channel_sign<D>(s.sym, c)) * s.grid[c * s.nodes + idx];
  }
};
// After the walls and the ghosts: a node beyond the plane is the reflection of its mirror.
template <int D, typename T>
struct SymmetryMirror {
  View<D, T> s;
  FLUME_HD void operator()(size_t idx) const {
    int side;
    const int64_t mi = s.symmetry_mirror(idx, side);
    if (side <= 0) return;
    for (int c = 0; c < s.channels; ++c)
      s.grid[c * s.nodes + idx] = mi < 0 ? T(0) : T(mpm::symmetry_channel_sign<D>(s.sym, c)) * s.grid[c * s.nodes + mi];
    s.gwall[idx] = mi < 0 ? 0 : s.gwall[mi];
  }
};

// Grid update, one node: momentum to velocity, gravity, the scene's walls (paper eq. 2) in scene order,
// then the domain box as a container; keeps the axes the walls hold (the J-bar average, the ghosts' mirrors).
// As MpmSolver::grid_update.
template <int D, typename T>
struct GridUpdate {
  View<D, T> s;
  T dt;
  FLUME_HD void operator()(size_t idx) const {
    for (int c = 0; c < mpm::kGhostPoolLanes * D; ++c) s.ghost_pool[c * s.nodes + idx] = T(0);
    const T m = s.grid[idx];
    if (m <= T(0)) {
      for (int c = 0; c < s.channels; ++c) s.grid[c * s.nodes + idx] = T(0);
      s.gwall[idx] = 0;
      s.ghost_mirror[idx] = -1;
      return;
    }
    int node[D];
    s.node_of(idx, node);
    // Beyond the symmetry plane: the mirror of its reflection, once that is updated (SymmetryMirror).
    const int sym_side = s.has_sym ? mpm::symmetry_side(s.sym, node[s.sym.axis]) : -1;
    if (sym_side > 0) {
      s.ghost_mirror[idx] = -1;
      return;
    }
    const double load_weight = sym_side == 0 ? 0.5 : 1.0;  // a load on the plane is half the whole's
    T v[D];
    for (int d = 0; d < D; ++d) v[d] = s.grid[(1 + d) * s.nodes + idx] / m + dt * s.gravity[d];
    double xn[D];
    for (int d = 0; d < D; ++d) xn[d] = mpm::node_coordinate(s.grid_lo_d[d], node[d], s.dx_d);
    // The particles' momentum alone, before gravity and the walls: what a ghost's image reflects (mpm::ghost_pool_terms).
    for (int d = 0; d < D; ++d) s.ghost_dv[d * s.nodes + idx] = s.grid[(1 + d) * s.nodes + idx] / m;
    mpm::GhostSearch<D> found;
    T v_free[D];
    for (int d = 0; d < D; ++d) v_free[d] = v[d];
    const unsigned held = mpm::apply_boundaries<D>(xn, m, v, dt, load_weight, s.dx_d, s.subcell_rate, s.walls,
                                                   nullptr, s.n_walls, s.container, s.impulse, found);
    if (s.probes.count > 0) {  // only nodes a wall acted on push
      double push[D];
      if (mpm::node_wall_push<D>(load_weight, m, v, v_free, push))
        mpm::add_probe_push<D>(s.probes, xn, push, s.probe_push);
    }
    s.ghost_mirror[idx] = -1;
    if (found.found()) {
      int mirror[D];
      for (int d = 0; d < D; ++d) mirror[d] = found.offset[d] + node[d];
      s.ghost_mirror[idx] = s.grid_index(mirror);
      s.ghost_axes[idx] = static_cast<uint8_t>(found.axes);
      s.ghost_wall[idx] = found.wall;
    }
    s.grid[(1 + D) * s.nodes + idx] /= m;
    s.grid[(2 + D) * s.nodes + idx] *= s.inv_cell_volume;  // the node's fill (mpm::fill_correction)
    for (int c = View<D, T>::kChannels; c < s.channels; ++c) s.grid[c * s.nodes + idx] /= m;  // FLIP's old velocity
    s.gwall[idx] = static_cast<uint8_t>(held);
    for (int d = 0; d < D; ++d) s.grid[(1 + d) * s.nodes + idx] = v[d];
  }
};

// Ghost nodes exchange tangential momentum with their reflection, every ghost of a mirror as one group
// (mpm::ghost_pool_velocity; GhostReflection::reflect on the CPU), once every node is updated, in three passes:
// the ghosts add their terms to their mirror's pool (atomically where a mirror is shared); each ghost computes
// its group's velocities from the pool and the mirror's untouched velocity, takes its own, adds its share of
// the image's push to its wall's load and keeps the mirror's; then the mirrors take theirs (every ghost of a
// group writes the same values).
template <int D, typename T>
FLUME_HD bool ghost_pair(const View<D, T>& s, size_t idx, int64_t& mi) {
  mi = s.ghost_mirror[idx];
  return mi >= 0 && s.grid[idx] > T(0) && s.grid[mi] > T(0) && s.gwall[mi] != mpm::all_axes<D>();
}
template <int D, typename T>
struct GhostPoolAdd {
  View<D, T> s;
  FLUME_HD void operator()(size_t idx) const {
    int64_t mi;
    if (!ghost_pair(s, idx, mi)) return;
    T vg[D], vpre[D], terms[mpm::kGhostPoolLanes * D];
    for (int d = 0; d < D; ++d) {
      vg[d] = s.grid[(1 + d) * s.nodes + idx];
      vpre[d] = s.ghost_dv[d * s.nodes + idx];
    }
    mpm::ghost_pool_terms<D>(vg, vpre, s.grid[idx], s.ghost_axes[idx], s.push_axes, terms);
    for (int c = 0; c < mpm::kGhostPoolLanes * D; ++c)
      if (terms[c] != T(0)) mpm::accumulate(&s.ghost_pool[c * s.nodes + mi], terms[c]);
  }
};
template <int D, typename T>
struct GhostExchange {
  View<D, T> s;
  FLUME_HD void operator()(size_t idx) const {
    int64_t mi;
    if (!ghost_pair(s, idx, mi)) return;
    T pool[mpm::kGhostPoolLanes * D], vm[D], u[D], push_dv[D];
    for (int c = 0; c < mpm::kGhostPoolLanes * D; ++c) pool[c] = s.ghost_pool[c * s.nodes + mi];
    for (int d = 0; d < D; ++d) vm[d] = s.grid[(1 + d) * s.nodes + mi];
    const unsigned held = s.gwall[mi];
    mpm::ghost_pool_velocity<D>(pool, vm, s.grid[mi], held, u, push_dv);
    const unsigned axes = s.ghost_axes[idx];
    const int wall = s.ghost_wall[idx];
    int node[D];
    s.node_of(idx, node);
    const double load_weight = s.has_sym && mpm::symmetry_side(s.sym, node[s.sym.axis]) == 0 ? 0.5 : 1.0;
    double push[D] = {};
    for (int d = 0; d < D; ++d) {
      if (mpm::ghost_takes_mean(axes, held, d)) s.grid[(1 + d) * s.nodes + idx] = u[d];
      s.ghost_dv[d * s.nodes + idx] = u[d];
      // The image's push, by this ghost's share of the pushing mass, is its wall's load (and the probes').
      const T nm = pool[2 * D + d];
      if ((axes & (1u << d)) && nm > T(0))
        push[d] = load_weight * double(s.grid[mi]) * double(push_dv[d] * (s.grid[idx] / nm));
      if (s.impulse && wall >= 0 && push[d] != 0.0) mpm::accumulate(&s.impulse[wall * D + d], -push[d]);
    }
    if (s.probes.count > 0) {
      double xg[D];
      for (int d = 0; d < D; ++d) xg[d] = mpm::node_coordinate(s.grid_lo_d[d], node[d], s.dx_d);
      mpm::add_probe_push<D>(s.probes, xg, push, s.probe_push);
    }
  }
};
template <int D, typename T>
struct GhostMirrorUpdate {
  View<D, T> s;
  FLUME_HD void operator()(size_t idx) const {
    int64_t mi;
    if (!ghost_pair(s, idx, mi)) return;
    for (int d = 0; d < D; ++d) s.grid[(1 + d) * s.nodes + mi] = s.ghost_dv[d * s.nodes + idx];
  }
};

// Debris (mpm/debris_k.h): the boxes as the host last stepped them.
struct Boxes {
  const RigidBoxView* views;
  const double* radius;
  int count;
};

// After the update, before the ghosts: a node with water in a box's band is that box's moving-wall node (it
// stays out of the J-bar average, as a wall node, and no ghost pairs with it). `body` gets the box or -1.
template <int D, typename T>
struct CouplingFind {
  View<D, T> s;
  Boxes boxes;
  double band;
  int32_t* body;
  FLUME_HD void operator()(size_t idx) const {
    body[idx] = -1;
    const T m = s.grid[idx];
    if (!(m > T(0))) return;
    int node[D];
    s.node_of(idx, node);
    CouplingNode c;
    if (!fill(idx, node, c)) return;
    body[idx] = c.body;
    s.gwall[idx] = mpm::all_axes<D>();
  }
  FLUME_HD bool fill(size_t idx, const int* node, CouplingNode& c) const {
    double xn[D];
    for (int d = 0; d < D; ++d) xn[d] = mpm::node_coordinate(s.grid_lo_d[d], node[d], s.dx_d);
    T v[D];
    for (int d = 0; d < D; ++d) v[d] = s.grid[(1 + d) * s.nodes + idx];
    return mpm::coupling_node<D, T>(boxes.views, boxes.radius, boxes.count, xn, band, idx, s.grid[idx],
                                    s.grid[(1 + D) * s.nodes + idx], v, s.law_d, s.strain_slope, c);
  }
};
// The nodes CouplingFind flagged, in storage order, as the host's exchange takes them.
template <int D, typename T>
struct CouplingGather {
  CouplingFind<D, T> find;
  const int64_t* index;
  CouplingNode* out;
  FLUME_HD void operator()(size_t k) const {
    int node[D];
    find.s.node_of(index[k], node);
    find.fill(index[k], node, out[k]);
  }
};
// The exchange's projected velocities back into the grid.
template <int D, typename T>
struct CouplingScatter {
  View<D, T> s;
  const CouplingNode* nodes;
  FLUME_HD void operator()(size_t k) const {
    for (int d = 0; d < D; ++d) s.grid[(1 + d) * s.nodes + nodes[k].id] = T(nodes[k].v[d]);
  }
};
// After G2P: the particles inside a box (`body` gets the box or -1), then those pushed back to its surface
// with their share for the box, in particle order.
template <int D, typename T>
struct PushFind {
  View<D, T> s;
  Boxes boxes;
  int32_t* body;
  FLUME_HD void operator()(size_t i) const {
    double x[3] = {0, 0, 0}, n[3];
    for (int d = 0; d < D; ++d) x[d] = s.x[d][i];
    body[i] = mpm::locate_box(boxes.views, boxes.radius, boxes.count, x, 0.0, n);
  }
};
template <int D, typename T>
struct PushOut {
  View<D, T> s;
  Boxes boxes;
  const int64_t* index;
  double* share;  // 6 per entry: impulse, then its moment about the origin
  int32_t* body;  // per entry
  int32_t* block;  // per entry: the particle's block, for the CPU's per-block partial sums
  FLUME_HD void operator()(size_t k) const {
    const size_t i = static_cast<size_t>(index[k]);
    double x[3] = {0, 0, 0}, v[3] = {0, 0, 0};
    for (int d = 0; d < D; ++d) {
      x[d] = s.x[d][i];
      v[d] = s.v[d][i];
    }
    body[k] = mpm::push_out_of_box(boxes.views, boxes.radius, boxes.count, s.rho_d * double(s.vol[i]), x, v,
                                   share + 6 * k);
    block[k] = s.pblk[i];
    for (int d = 0; d < D; ++d) {
      s.x[d][i] = T(x[d]);
      s.v[d][i] = T(v[d]);
    }
  }
};
struct IsBody {
  FLUME_HD bool operator()(int32_t b) const { return b >= 0; }
};

// G2P, one particle: velocity, APIC matrix, well-balanced J-bar strain (wall nodes left out of the average
// and the rest renormalised) and position. As MpmSolver::g2p, in the same summation order.
template <int D, typename T>
struct G2P {
  View<D, T> s;
  mpm::G2pConstants<D, T> g2p;
  // Particle i from its nodes' values: read(node, r) sets r to the node's velocity (D), mass-weighted strain,
  // fill and wall flag, as GridUpdate left them, and with FLIP the old velocity (D).
  template <typename Read>
  FLUME_HD void update(size_t i, const Read& read) const {
    const T dx = s.dx;
    const T cscale = T(4) * s.inv_dx * s.inv_dx;
    int base[D];
    T w[D][3], f[D];
    for (int d = 0; d < D; ++d) {
      const T xg = (s.x[d][i] - s.grid_lo[d]) * s.inv_dx;
      base[d] = mpm::stencil_base(xg, f[d]);
      mpm::bspline_weights(f[d], w[d]);
    }
    T vn[D] = {}, vo[D] = {}, Cn[D * D] = {}, Jg = 0, Fg = 0, wsum = 0;
    const bool flip = s.channels > View<D, T>::kChannels;
    constexpr int kStencil = mpm::Pow<D>::of(3);
    for (int q = 0; q < kStencil; ++q) {
      int off[D], node[D];
      for (int d = D - 1, r = q; d >= 0; --d, r /= 3) off[d] = r % 3;
      T wt = w[0][off[0]];
      for (int d = 1; d < D; ++d) wt *= w[d][off[d]];
      T dist[D];
      for (int d = 0; d < D; ++d) {
        node[d] = base[d] + off[d];
        dist[d] = (T(off[d]) - f[d]) * dx;
      }
      T r[2 * D + 3];
      read(node, r);
      if (flip)
        for (int a = 0; a < D; ++a) vo[a] += wt * r[D + 3 + a];
      T u[D];
      for (int a = 0; a < D; ++a) {
        u[a] = wt * r[a];
        vn[a] += u[a];
      }
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) Cn[a * D + b] += u[a] * dist[b];
      const T wj = r[D + 2] != T(0) ? T(0) : wt;
      Jg += wj * r[D];
      Fg += wj * r[D + 1];
      wsum += wj;
    }
    for (int k = 0; k < D * D; ++k) Cn[k] *= cscale;
    if (flip)
      for (int a = 0; a < D; ++a) vn[a] = mpm::flip_velocity(vn[a], s.v[a][i], vo[a], s.flip);
    T xp[D], e = s.e[i];
    for (int d = 0; d < D; ++d) xp[d] = s.x[d][i];
    s.fill_work[i] = mpm::g2p_particle<D>(g2p, Jg, Fg, wsum, s.vol[i], e, xp, vn, Cn);
    s.e[i] = e;
    for (int d = 0; d < D; ++d) {
      s.v[d][i] = vn[d];
      s.x[d][i] = xp[d];
    }
    for (int k = 0; k < D * D; ++k) s.C[k][i] = Cn[k];
  }
};

// G2P through the block's tile (BlockTile): the tile is read from the grid once, then each particle gathers from
// it.
template <int D, typename T>
struct G2PTiled : BlockTile<D> {
  using Tile = BlockTile<D>;
  G2P<D, T> g2p;
  // Velocity, strain, fill, wall flag; with FLIP the old velocity.
  FLUME_HD int values() const { return g2p.s.channels > View<D, T>::kChannels ? 2 * D + 3 : D + 3; }
  FLUME_HD int tile_values() const { return Tile::kEntries * values(); }
  FLUME_HD void load(size_t g, int v, T* tile) const {
    const View<D, T>& s = g2p.s;
    int blk[D], lo[D], node[D];
    this->corner(g, blk, lo);
    Tile::entry_node(v, lo, node);
    const size_t idx = s.node_index(static_cast<int32_t>(g), blk, node);
    for (int a = 0; a < D; ++a) tile[a * Tile::kEntries + v] = s.grid[(1 + a) * s.nodes + idx];
    tile[D * Tile::kEntries + v] = s.grid[(1 + D) * s.nodes + idx];
    tile[(D + 1) * Tile::kEntries + v] = s.grid[(2 + D) * s.nodes + idx];
    tile[(D + 2) * Tile::kEntries + v] = s.gwall[idx] ? T(1) : T(0);
    for (int a = 0; D + 3 + a < values(); ++a)
      tile[(D + 3 + a) * Tile::kEntries + v] = s.grid[(D + 3 + a) * s.nodes + idx];
  }
  FLUME_HD void item(size_t g, size_t i, T* tile) const {
    int blk[D], lo[D];
    this->corner(g, blk, lo);
    g2p.update(i, [&](const int* node, T* r) {
      const int v = Tile::entry(node, lo);
      for (int k = 0; k < values(); ++k) r[k] = tile[k * Tile::kEntries + v];
    });
  }
  FLUME_HD void flush(size_t, int, const T*) const {}
};

// What the step's audit needs from all particles: energies, the largest speed, the first bad particle and
// whether any particle drifted out of its sorted block.
struct Audit {
  double vmax2 = 0, ke = 0, pe = 0, el = 0;
  double fill_work = 0;  // energy the volume constraint added (MpmSolver::g2p)
  long long bad = -1;  // lowest index of a non-finite or escaped particle
  int bad_kind = 0;    // 1 non-finite, 2 left the domain
  int resort = 0;
};
struct AuditJoin {
  FLUME_HD Audit operator()(const Audit& a, const Audit& b) const {
    Audit r;
    r.vmax2 = a.vmax2 > b.vmax2 ? a.vmax2 : b.vmax2;
    r.ke = a.ke + b.ke;
    r.pe = a.pe + b.pe;
    r.el = a.el + b.el;
    r.fill_work = a.fill_work + b.fill_work;
    const bool take_a = a.bad >= 0 && (b.bad < 0 || a.bad < b.bad);
    r.bad = take_a ? a.bad : b.bad;
    r.bad_kind = take_a ? a.bad_kind : b.bad_kind;
    r.resort = a.resort | b.resort;
    return r;
  }
};
template <int D, typename T>
struct AuditParticle {
  View<D, T> s;
  double lo_ok[D], hi_ok[D];
  FLUME_HD Audit operator()(size_t i) const {
    Audit r;
    r.fill_work = s.fill_work[i];
    const T e = s.e[i];
    bool ok = is_finite(double(e)) && e > T(-1);
    bool inside = true;
    double v2 = 0, gx = 0;
    int blk[D];
    unpack_key<D>(s.pkeys[s.pblk[i]], blk);
    for (int d = 0; d < D; ++d) {
      const T xn = s.x[d][i], vn = s.v[d][i];
      ok = ok && is_finite(double(xn)) && is_finite(double(vn));
      inside = inside && xn >= T(lo_ok[d]) && xn <= T(hi_ok[d]);
      v2 += double(vn) * vn;
      gx += double(s.gravity[d]) * xn;
      T f;
      const int nr = mpm::stencil_base((xn - s.grid_lo[d]) * s.inv_dx, f) - (blk[d] * kBlock - 1);
      if (nr < 0 || nr > kBlock + 1) r.resort = 1;
    }
    if (!ok || !inside) {
      r.bad = static_cast<long long>(i);
      r.bad_kind = ok ? 2 : 1;
      return r;
    }
    r.vmax2 = v2;
    const double V = s.vol[i], mp = s.rho_d * V;
    r.ke = 0.5 * mp * v2;
    r.pe = -mp * gx;
    r.el = V * s.law_d.energy_density(double(e));
    return r;
  }
};

// The instruments' particle sums (solver/particle_sums.h) on the device: particle i as a term reads it, and
// the reduction of a term's values over all particles.
template <int D, typename T>
struct DeviceParticle {
  const View<D, T>& s;
  size_t i;
  FLUME_HD double x(int d) const { return double(s.x[d][i]); }
  FLUME_HD double v(int d) const { return double(s.v[d][i]); }
  FLUME_HD double volume() const { return double(s.vol[i]); }
  FLUME_HD double pressure() const { return s.law_d.pressure(double(s.e[i])); }
};
struct Sums {
  double v[kMaxParticleSum] = {};
};
struct SumsJoin {
  FLUME_HD Sums operator()(const Sums& a, const Sums& b) const {
    Sums r;
    for (int k = 0; k < kMaxParticleSum; ++k) r.v[k] = a.v[k] + b.v[k];
    return r;
  }
};
template <int D, typename T, class Term>
struct SumTerm {
  View<D, T> s;
  Term term;
  FLUME_HD Sums operator()(size_t i) const {
    Sums r;
    term(DeviceParticle<D, T>{s, i}, r.v);
    return r;
  }
};

template <typename T>
T* raw(thr::device_vector<T>& v) {
  return thr::raw_pointer_cast(v.data());
}

template <int D, typename T>
class MpmCuda final : public Simulation, private mpm::SceneConstants<D, T> {
  using V = View<D, T>;
  using K = mpm::SceneConstants<D, T>;  // the scene's constants, as the CPU's (constants.h)
  using K::dx_, K::inv_dx_, K::grid_lo_, K::gravity_, K::mu_, K::psi_, K::flip_, K::law_, K::law_d_, K::strain_slope_, K::c_;
  static constexpr int kNodes = V::kNodes;
  static constexpr int kNbr = V::kNbr;
  int channels_ = V::kChannels;  // V::kMaxChannels with FLIP

 public:
  MpmCuda(const Scene& scene, const SimulationOptions&)
      : mpm::SceneConstants<D, T>(scene), scene_(scene), instruments_(scene_) {
    if (flip_ > T(0)) channels_ = V::kMaxChannels;
    if (scene.debris.present) {
      if constexpr (D != 3) throw InputError(scene.file, "debris", "debris need a 3D scene");
      debris_ = std::make_unique<DebrisCoupling>(scene_);
      const auto& r = debris_->bounding_radii();
      box_radius_.assign(r.begin(), r.end());
    }
    seed_particles();
    if (scene.inflow.present) {  // the buffer of the inflow boundary (solver/inflow.h), on host arrays
      to_host();
      inflow_ = std::make_unique<InflowBoundary<D, T>>(scene_, spacing_, host_arrays());
      inflow_->seed();
      to_device();
      run_.mass = water_mass(h_.vol, rho_);
    }
    setup_boundaries();
    sort_particles();
    run_.start_audit(scene_, energy(), inflow_ ? inflow_->energy_scale() : 0.0);
    instruments_.sample(*this, 0.0, 0.0, true);
  }

  RunStatus step() override {
    if (run_.status != RunStatus::kRunning) return run_.status;
    const double dt = run_.next_dt(scene_, dx_, c_);
    if (dt == 0) return run_.status;
    if (needs_sort_) sort_particles();
    V s = view();
    s.flip = T(mpm::flip_for_step(double(flip_), dt, dx_, c_));
    thr::fill(thr::device, grid_.begin(), grid_.end(), T(0));
    if (has_loads_) thr::fill(thr::device, impulse_.begin(), impulse_.end(), 0.0);
    if (s.probes.count) thr::fill(thr::device, probe_push_d_.begin(), probe_push_d_.end(), 0.0);
    // The vacuum's hold: an upward force f(t) m |g| on the held water (as MpmSolver::p2g).
    const T lift = T(double(dt) * scene_.basin.forcing.hold(run_.time) * std::fabs(scene_.solver.gravity[D - 1]));
    const BlockTile<D> tile{raw(pkeys_), raw(pstart_)};
    mpm::tiled_for<T>(pkeys_.size(), P2GTiled<D, T>{tile, {s, T(dt), lift}});
    if (s.has_sym) mpm::parallel_for(s.nodes, SymmetryFold<D, T>{s});
    mpm::parallel_for(s.nodes, GridUpdate<D, T>{s, T(dt)});
    if (debris_) find_coupling_nodes(s);
    mpm::parallel_for(s.nodes, GhostPoolAdd<D, T>{s});
    mpm::parallel_for(s.nodes, GhostExchange<D, T>{s});
    mpm::parallel_for(s.nodes, GhostMirrorUpdate<D, T>{s});
    if (s.has_sym) mpm::parallel_for(s.nodes, SymmetryMirror<D, T>{s});
    if (has_loads_) thr::copy(impulse_.begin(), impulse_.end(), load_impulse_.begin());
    if (s.probes.count) thr::copy(probe_push_d_.begin(), probe_push_d_.end(), probe_push_.begin());
    if (debris_) couple_debris(s, double(dt));
    mpm::tiled_for<T>(pkeys_.size(), G2PTiled<D, T>{tile, {s, g2p_constants(s, T(dt))}});
    if (debris_) push_out_of_debris(s);
    host_fresh_ = false;
    audit(T(dt));
    const auto inflow = [&](double t0, double t1) { apply_inflow(t0, t1); };
    return run_.end_step(scene_, dt, inflow_ != nullptr, inflow, instruments_, *this, load_impulse_);
  }

  double time() const override { return run_.time; }
  double last_dt() const override { return run_.dt; }
  long steps() const override { return run_.steps; }
  size_t particle_count() const override { return n_; }
  const DebrisCoupling* debris() const override { return debris_.get(); }
  DebrisCoupling* debris() override { return debris_.get(); }
  double total_mass() const override { return run_.mass; }
  const Record& record() const override { return instruments_.record(); }
  const std::string& message() const override { return run_.message; }

  void particle_positions(std::vector<double>& xyz) const override {
    sync_host();
    interleave_axes<D>(hx_, n_, xyz);
  }
  void particle_velocities(std::vector<double>& vel) const override {
    sync_host();
    interleave_axes<D>(hv_, n_, vel);
  }
  void particle_pressures(std::vector<double>& p) const override {
    std::vector<T> e(n_);
    thr::copy(e_.begin(), e_.end(), e.begin());
    p.resize(n_);
    for (size_t i = 0; i < n_; ++i) p[i] = law_d_.pressure(double(e[i]));
  }
  size_t grid_bytes() const override {
    return grid_.capacity() * sizeof(T) + gwall_.capacity() + ghost_axes_.capacity() +
           ghost_mirror_.capacity() * sizeof(int64_t) + ghost_dv_.capacity() * sizeof(T) +
           ghost_pool_.capacity() * sizeof(T) + ghost_wall_.capacity() * sizeof(int32_t) +
           (gkeys_.capacity() + pkeys_.capacity()) * sizeof(uint64_t) + p_nbr_.capacity() * sizeof(int32_t);
  }
  size_t active_blocks() const override { return gkeys_.size(); }
  size_t particle_bytes() const override { return n_ * (sizeof(T) * (2 * D + D * D + 2) + sizeof(int32_t)); }

  void momentum(double linear[3], double angular[3]) const override {
    sync_host();
    if (!host_vol_fresh_) sync_volume();
    std::vector<T> C[D * D];
    for (int k = 0; k < D * D; ++k) download(C_[k], C[k]);
    mpm::particles_momentum<D>(n_, rho_, dx_, hx_, hv_, C, hvol_, linear, angular);
  }

  void set_rigid_velocity(const double v0[3], const double omega[3], const double centre[3]) override {
    sync_host();
    std::vector<T> C[D * D];
    for (int k = 0; k < D * D; ++k) C[k].resize(n_);
    run_.max_speed = mpm::impose_rigid_motion<D>(n_, v0, omega, centre, hx_, hv_, C);
    for (int d = 0; d < D; ++d) thr::copy(hv_[d].begin(), hv_[d].end(), v_[d].begin());
    for (int k = 0; k < D * D; ++k) thr::copy(C[k].begin(), C[k].end(), C_[k].begin());
    run_.restart_audit(energy());
  }

  // As MpmSolver::checkpoint: everything a step reads that an earlier step wrote, the particles through the
  // host, and the block each particle was last sorted into (between sorts a particle may drift into the next
  // block's tile margin without a re-sort, and the sum order of P2G follows the particle order): the block
  // lists and the grid are rebuilt from those, so a resumed run repeats the uninterrupted one step for step.
  void checkpoint(StateArchive& ar) override {
    ar.section(std::string("mpm cuda ") + std::to_string(D) + "D " + (sizeof(T) == 4 ? "float" : "double"));
    for (int d = 0; d < D; ++d) {
      archive(ar, x_[d]);
      archive(ar, v_[d]);
    }
    for (auto& c : C_) archive(ar, c);
    archive(ar, e_);
    archive(ar, vol_);
    archive(ar, held_);
    archive(ar, tag_);
    archive(ar, keys_);
    run_.checkpoint(ar, scene_);  // refuses an unstable run; a finished one resumed to a later end runs on
    ar(needs_sort_);
    instruments_.checkpoint(ar);
    ar.expect("inflow", inflow_ ? 1 : 0);
    if (inflow_) inflow_->checkpoint(ar);
    ar.expect("debris", debris_ ? 1 : 0);
    if (debris_) debris_->checkpoint(ar);
    if (!ar.loading()) return;
    n_ = x_[0].size();
    if (!mpm::particle_lengths_agree<D>(n_, x_, v_, C_, e_, vol_, held_, tag_))
      ar.fail("particles", "particle arrays of different lengths");
    resize_work();
    if (!needs_sort_) {
      if (keys_.size() != n_) ar.fail("particles", "block keys for a different particle count");
      build_blocks();
    }
  }

  // --- read access for the instruments: sums on the device (solver/particle_sums.h); the rest from host
  // mirrors, refreshed lazily ---
  static constexpr bool kSumsOnDevice = true;
  // The pressure probes read the walls' push at the nodes (solver/mpm/probe_k.h), summed on the device.
  static constexpr bool kProbesReadWallPush = true;
  const std::vector<double>& probe_push() const { return probe_push_; }
  template <class Term>
  void sum_particles(const Term& term, double* sum) const {
    static_assert(Term::kValues <= kMaxParticleSum, "a term sums at most kMaxParticleSum values");
    const SumTerm<D, T, Term> op{const_cast<MpmCuda*>(this)->view(), term};
    thr::counting_iterator<size_t> first(0);
    const Sums r = thr::transform_reduce(thr::device, first, first + n_, op, Sums{}, SumsJoin{});
    for (int k = 0; k < Term::kValues; ++k) sum[k] = r.v[k];
  }
  int dim() const { return D; }
  size_t n() const { return n_; }
  T x(int d, size_t i) const {
    if (!host_fresh_) sync_host();
    return hx_[d][i];
  }
  T v(int d, size_t i) const {
    if (!host_fresh_) sync_host();
    return hv_[d][i];
  }
  T volume(size_t i) const {  // reference volume: the particle's mass over rho
    if (!host_vol_fresh_) sync_volume();
    return hvol_[i];
  }
  double max_speed() const { return run_.max_speed; }

  Energy energy() const {
    const Audit a = reduce_audit();
    return {a.ke, a.pe, a.el, debris_ ? debris_->energy() : 0.0};
  }
  const Energy& last_energy() const { return run_.last_energy; }
  const Scene& scene() const { return scene_; }

 private:
  // As MpmSolver::seed_particles: a regular lattice of ppc^(1/D) particles per cell per axis in each water
  // box, hydrostatically preloaded where asked.
  void seed_particles() {
    spacing_ = particle_spacing(scene_);
    rho_ = scene_.fluid.density;
    // Water is not seeded inside a debris box: the box displaces it.
    const Seeds seeds = seed_water<D>(scene_, spacing_, displaced_by<D>(debris_.get()));
    n_ = seeds.size();
    for (int d = 0; d < D; ++d) {
      const std::vector<T> xd(seeds.x[d].begin(), seeds.x[d].end());
      x_[d].assign(xd.begin(), xd.end());
      v_[d].assign(n_, T(0));
    }
    for (int k = 0; k < D * D; ++k) C_[k].assign(n_, T(0));
    const std::vector<T> strain(seeds.strain.begin(), seeds.strain.end());
    e_.assign(strain.begin(), strain.end());
    const std::vector<T> vols(seeds.volume.begin(), seeds.volume.end());
    vol_.assign(vols.begin(), vols.end());
    host_vol_fresh_ = false;
    if (seeds.any_held) {
      const std::vector<T> held(seeds.held.begin(), seeds.held.end());
      held_.assign(held.begin(), held.end());
    }
    fill_work_.assign(e_.size(), 0.0);
    run_.mass = water_mass(vols, rho_);
    pblk_.resize(n_);
    keys_.resize(n_);
    order_.resize(n_);
    tmp_.resize(n_);
  }

  void setup_boundaries() {
    const std::vector<Wall<D, T>> walls = mpm::scene_walls<D, T>(scene_);
    has_sym_ = mpm::scene_symmetry_plane<D>(scene_, grid_lo_, dx_, sym_) ? 1 : 0;
    if (has_sym_ && debris_)
      throw InputError(scene_.file, "boundaries", "a symmetry plane cannot be used with debris (the bodies would "
                                                  "need their mirror images): model the full span");
    walls_.assign(walls.begin(), walls.end());
    n_walls_ = static_cast<int>(walls.size());
    container_ = mpm::scene_container<D, T>(scene_);
    load_impulse_.assign(walls.size() * D, 0.0);
    has_loads_ = !scene_.instruments.loads.empty() && !walls.empty();
    impulse_.assign(walls.size() * D, 0.0);
    const std::vector<double> geometry = mpm::probe_geometry(scene_);
    probe_geometry_.assign(geometry.begin(), geometry.end());
    probe_push_d_.assign(scene_.instruments.pressure_probes.size(), 0.0);
    probe_push_.assign(scene_.instruments.pressure_probes.size(), 0.0);
  }

  V view() {
    V s{};
    for (int d = 0; d < D; ++d) {
      s.x[d] = raw(x_[d]);
      s.v[d] = raw(v_[d]);
      s.grid_lo[d] = T(grid_lo_[d]);
      s.grid_lo_d[d] = grid_lo_[d];
      s.gravity[d] = gravity_[d];
      s.strain_slope[d] = strain_slope_[d];
    }
    for (int k = 0; k < D * D; ++k) s.C[k] = raw(C_[k]);
    s.e = raw(e_);
    s.vol = raw(vol_);
    s.held = held_.empty() ? nullptr : raw(held_);
    s.fill_work = raw(fill_work_);
    s.pblk = raw(pblk_);
    s.pkeys = raw(pkeys_);
    s.p_nbr = raw(p_nbr_);
    s.gkeys = raw(gkeys_);
    s.grid = raw(grid_);
    s.channels = channels_;  // s.flip is the step's (MpmCuda::step, mpm::flip_for_step)
    s.gwall = raw(gwall_);
    s.ghost_mirror = raw(ghost_mirror_);
    s.ghost_axes = raw(ghost_axes_);
    s.ghost_dv = raw(ghost_dv_);
    s.ghost_pool = raw(ghost_pool_);
    s.ghost_wall = raw(ghost_wall_);
    s.nodes = gkeys_.size() * kNodes;
    s.dx = T(dx_);
    s.inv_dx = inv_dx_;
    s.rho = T(rho_);
    s.rho_d = rho_;
    s.law = law_;
    s.push_axes = mpm::image_push_axes<D>(scene_.solver.gravity.data());
    s.has_sym = has_sym_;
    s.subcell_rate = mpm::subcell_rate0(c_, dx_);
    s.sym = sym_;
    s.law_d = law_d_;
    s.mu = mu_;
    s.psi = psi_;
    s.fill_tol = T(mpm::kFillTolerance);
    s.inv_cell_volume = T(1) / T(std::pow(dx_, D));
    s.dx_d = dx_;
    s.walls = raw(walls_);
    s.n_walls = n_walls_;
    s.container = container_;
    s.impulse = has_loads_ ? raw(impulse_) : nullptr;
    // The view's pointers into probe_geometry_ (points, then normals) are device addresses.
    s.probes = mpm::ProbeFaces{};
    s.probes.count = static_cast<int>(probe_push_.size());
    s.probes.point = s.probes.count ? raw(probe_geometry_) : nullptr;
    s.probes.normal = s.probes.count ? raw(probe_geometry_) + 3 * s.probes.count : nullptr;
    s.probes.dx = dx_;
    s.probes.depth = mpm::kProbeDepthCells * dx_;
    if (has_sym_) {
      s.probes.sym_axis = sym_.axis;
      s.probes.sym_at = sym_.at;
    }
    s.probe_push = s.probes.count ? raw(probe_push_d_) : nullptr;
    return s;
  }

  mpm::G2pConstants<D, T> g2p_constants(const V& s, T dt) const {
    mpm::G2pConstants<D, T> k;
    k.dt = dt;
    k.psi = psi_;
    k.fill_rate = T(mpm::fill_rate(double(dt), c_, dx_));
    k.fill_tol = s.fill_tol;
    for (int d = 0; d < D; ++d) k.slope[d] = strain_slope_[d];
    k.law_d = s.law_d;
    k.has_sym = has_sym_ != 0;
    k.sym = sym_;
    return k;
  }

  // Sorts particles by block and rebuilds the sparse block lists, all on the device.
  void sort_particles() {
    mpm::parallel_for(n_, SortKey<D, T>{view(), raw(keys_)});
    thr::sequence(thr::device, order_.begin(), order_.end());
    thr::stable_sort_by_key(thr::device, keys_.begin(), keys_.end(), order_.begin());
    auto permute = [&](thr::device_vector<T>& a) {
      thr::gather(thr::device, order_.begin(), order_.end(), a.begin(), tmp_.begin());
      a.swap(tmp_);
    };
    for (int d = 0; d < D; ++d) {
      permute(x_[d]);
      permute(v_[d]);
    }
    for (int k = 0; k < D * D; ++k) permute(C_[k]);
    permute(e_);
    permute(vol_);
    host_vol_fresh_ = false;
    if (!held_.empty()) permute(held_);
    if (!tag_.empty()) permute(tag_);
    build_blocks();
  }

  // The particle blocks, each particle's block index, the grid blocks and the neighbour tables, from the
  // particles' block keys (keys_, in particle order) as the last sort assigned them.
  void build_blocks() {
    // Particle blocks, and each particle's block index.
    pkeys_.resize(n_);
    pkeys_.resize(thr::unique_copy(thr::device, keys_.begin(), keys_.end(), pkeys_.begin()) - pkeys_.begin());
    thr::lower_bound(thr::device, pkeys_.begin(), pkeys_.end(), keys_.begin(), keys_.end(), pblk_.begin());
    // Each particle block's first particle (pblk_ is sorted), and the count at the end: P2GTiled's ranges.
    pstart_.resize(pkeys_.size() + 1);
    thr::counting_iterator<int32_t> block0(0);
    thr::lower_bound(thr::device, pblk_.begin(), pblk_.end(), block0, block0 + pstart_.size(), pstart_.begin());
    // Grid blocks: the 3^D neighbourhood of every particle block; each particle block's neighbour table.
    const size_t nn = pkeys_.size() * kNbr;
    nbr_keys_.resize(nn);
    mpm::parallel_for(nn, NeighbourKey<D>{raw(pkeys_), raw(nbr_keys_)});
    gkeys_.resize(nn);
    thr::copy(thr::device, nbr_keys_.begin(), nbr_keys_.end(), gkeys_.begin());
    thr::sort(thr::device, gkeys_.begin(), gkeys_.end());
    gkeys_.resize(thr::unique(thr::device, gkeys_.begin(), gkeys_.end()) - gkeys_.begin());
    p_nbr_.resize(nn);
    thr::lower_bound(thr::device, gkeys_.begin(), gkeys_.end(), nbr_keys_.begin(), nbr_keys_.end(),
                     p_nbr_.begin());
    const size_t nodes = gkeys_.size() * kNodes;
    grid_.resize(static_cast<size_t>(channels_) * nodes);
    gwall_.resize(nodes);
    ghost_mirror_.resize(nodes);
    ghost_axes_.resize(nodes);
    ghost_dv_.resize(D * nodes);
    ghost_pool_.resize(mpm::kGhostPoolLanes * D * nodes);
    ghost_wall_.resize(nodes);
    needs_sort_ = false;
  }

  Audit reduce_audit() const {
    V s = const_cast<MpmCuda*>(this)->view();
    AuditParticle<D, T> op{s, {}, {}};
    for (int d = 0; d < D; ++d) {
      op.lo_ok[d] = scene_.domain_lo[d] - dx_;
      op.hi_ok[d] = scene_.domain_hi[d] + dx_;
    }
    thr::counting_iterator<size_t> first(0);
    return thr::transform_reduce(thr::device, first, first + n_, op, Audit{}, AuditJoin{});
  }

  // The CPU's checks after G2P: NaN/Inf or escaped particles, then energy growth; and the re-sort flag.
  void audit(T dt) {
    const Audit a = reduce_audit();
    run_.max_speed = std::sqrt(a.vmax2);
    needs_sort_ = a.resort != 0;
    run_.energy0 += a.fill_work;  // the volume constraint's work is supplied energy (as in MpmSolver::g2p)
    const double t_new = run_.time + double(dt);
    if (a.bad >= 0) {
      double xp[D];
      for (int d = 0; d < D; ++d) xp[d] = double(T(x_[d][a.bad]));
      fail(mpm::bad_particle_message(a.bad_kind, t_new, run_.steps + 1, double(dt), a.bad, xp, D));
      return;
    }
    const double e_debris = debris_ ? debris_->energy() : 0.0;
    const double e = a.ke + a.pe + a.el + e_debris;
    if (e > run_.energy0 + run_.energy_slack) {
      sync_host();
      fail(mpm::energy_growth_message<D>(t_new, run_.steps + 1, e, run_.energy0, run_.max_speed, hx_, hv_, n_));
    }
    run_.last_energy = {a.ke, a.pe, a.el, e_debris};
  }

  // Debris, as MpmSolver::grid_update and MpmSolver::g2p (debris_coupling.h): the boxes as the host holds them.
  Boxes boxes() {
    const auto& views = debris_->views();
    box_views_.assign(views.begin(), views.end());
    return {raw(box_views_), raw(box_radius_), static_cast<int>(views.size())};
  }
  // The nodes in the boxes' bands with the velocities the update gave them, before the ghosts change any.
  void find_coupling_nodes(const V& s) {
    node_body_.resize(s.nodes);
    const CouplingFind<D, T> f{s, boxes(), mpm::kCouplingBandCells * dx_, raw(node_body_)};
    mpm::parallel_for(s.nodes, f);
    picked_.resize(s.nodes);
    thr::counting_iterator<int64_t> first(0);
    const size_t k = thr::copy_if(thr::device, first, first + s.nodes, node_body_.begin(), picked_.begin(), IsBody{}) -
                     picked_.begin();
    coupling_.resize(k);
    mpm::parallel_for(k, CouplingGather<D, T>{f, raw(picked_), raw(coupling_)});
    h_coupling_.resize(k);
    thr::copy(coupling_.begin(), coupling_.begin() + k, h_coupling_.begin());
  }
  // The exchange on the host (nodes in storage order, which is the CPU's grid order), then the projected
  // velocities back into the grid.
  void couple_debris(const V& s, double dt) {
    debris_->exchange(h_coupling_, dt);
    thr::copy(h_coupling_.begin(), h_coupling_.end(), coupling_.begin());
    mpm::parallel_for(h_coupling_.size(), CouplingScatter<D, T>{s, raw(coupling_)});
  }
  // Particles inside a box go back to its surface; their lost momentum goes to the box, summed as the CPU sums
  // it (per particle block, then over the blocks in order) so that the sums do not depend on the backend.
  void push_out_of_debris(const V& s) {
    const Boxes b = boxes();
    particle_body_.resize(n_);
    mpm::parallel_for(n_, PushFind<D, T>{s, b, raw(particle_body_)});
    picked_.resize(std::max(picked_.size(), n_));
    thr::counting_iterator<int64_t> first(0);
    const size_t k = thr::copy_if(thr::device, first, first + n_, particle_body_.begin(), picked_.begin(), IsBody{}) -
                     picked_.begin();
    const int nb = b.count;
    std::vector<double> total(static_cast<size_t>(nb) * 6, 0.0);
    if (k > 0) {
      push_share_.resize(6 * k);
      push_body_.resize(k);
      push_block_.resize(k);
      mpm::parallel_for(k, PushOut<D, T>{s, b, raw(picked_), raw(push_share_), raw(push_body_), raw(push_block_)});
      std::vector<double> share(6 * k);
      std::vector<int32_t> body(k), block(k);
      thr::copy(push_share_.begin(), push_share_.begin() + 6 * k, share.begin());
      thr::copy(push_body_.begin(), push_body_.begin() + k, body.begin());
      thr::copy(push_block_.begin(), push_block_.begin() + k, block.begin());
      std::vector<double> in_block(total.size(), 0.0);
      for (size_t j = 0; j < k; ++j) {
        if (j > 0 && block[j] != block[j - 1]) {
          for (size_t q = 0; q < total.size(); ++q) total[q] += in_block[q];
          std::fill(in_block.begin(), in_block.end(), 0.0);
        }
        for (int q = 0; q < 6; ++q) in_block[body[j] * 6 + q] += share[6 * j + q];
      }
      for (size_t q = 0; q < total.size(); ++q) total[q] += in_block[q];
    }
    for (int body = 0; body < nb; ++body) debris_->add_particle_impulse(body, &total[body * 6], &total[body * 6 + 3]);
  }

  // Per-particle work arrays, after the particle count changed.
  void resize_work() {
    fill_work_.assign(n_, 0.0);
    pblk_.resize(n_);
    keys_.resize(n_);
    order_.resize(n_);
    tmp_.resize(n_);
    host_fresh_ = host_vol_fresh_ = false;
  }

  // The inflow works on host arrays (solver/inflow.h): the particles go to the host and back around it each
  // step, O(n) copies that a device-side buffer would save.
  ParticleArrays<D, T> host_arrays() {
    ParticleArrays<D, T> a;
    for (int d = 0; d < D; ++d) {
      a.x[d] = &h_.x[d];
      a.v[d] = &h_.v[d];
    }
    for (int k = 0; k < D * D; ++k) a.C[k] = &h_.C[k];
    a.e = &h_.e;
    a.vol = &h_.vol;
    a.held = &h_.held;
    a.tag = &h_.tag;
    return a;
  }
  static void download(const thr::device_vector<T>& a, std::vector<T>& h) {
    h.resize(a.size());
    thr::copy(a.begin(), a.end(), h.begin());
  }
  void to_host() {
    for (int d = 0; d < D; ++d) {
      download(x_[d], h_.x[d]);
      download(v_[d], h_.v[d]);
    }
    for (int k = 0; k < D * D; ++k) download(C_[k], h_.C[k]);
    download(e_, h_.e);
    download(vol_, h_.vol);
    download(held_, h_.held);
    download(tag_, h_.tag);
  }
  void to_device() {
    for (int d = 0; d < D; ++d) {
      x_[d].assign(h_.x[d].begin(), h_.x[d].end());
      v_[d].assign(h_.v[d].begin(), h_.v[d].end());
    }
    for (int k = 0; k < D * D; ++k) C_[k].assign(h_.C[k].begin(), h_.C[k].end());
    e_.assign(h_.e.begin(), h_.e.end());
    vol_.assign(h_.vol.begin(), h_.vol.end());
    held_.assign(h_.held.begin(), h_.held.end());
    tag_.assign(h_.tag.begin(), h_.tag.end());
    n_ = h_.x[0].size();
    resize_work();
  }
  // As MpmSolver::apply_inflow: the inflow moves, adds and removes particles after the step; the energy audit
  // is told what it did.
  void apply_inflow(double t0, double t1) {
    to_host();
    const auto change = inflow_->apply(t0, t1);
    run_.energy0 += change.energy;
    to_device();
    if (change.structural) run_.mass = water_mass(h_.vol, rho_);
    needs_sort_ = needs_sort_ || change.structural;
  }

  // A device array written to or read from the archive through a host copy.
  template <typename U>
  static void archive(StateArchive& ar, thr::device_vector<U>& a) {
    std::vector<U> h(ar.loading() ? 0 : a.size());
    if (!ar.loading()) thr::copy(a.begin(), a.end(), h.begin());
    ar(h);
    if (ar.loading()) a.assign(h.begin(), h.end());
  }

  void fail(const std::string& what) { run_.fail(what); }

  void sync_host() const {
    for (int d = 0; d < D; ++d) {
      hx_[d].resize(n_);
      hv_[d].resize(n_);
      thr::copy(x_[d].begin(), x_[d].end(), hx_[d].begin());
      thr::copy(v_[d].begin(), v_[d].end(), hv_[d].begin());
    }
    host_fresh_ = true;
  }
  // The reference volumes change only when the particles are sorted: copied to the host only then.
  void sync_volume() const {
    hvol_.resize(n_);
    thr::copy(vol_.begin(), vol_.end(), hvol_.begin());
    host_vol_fresh_ = true;
  }

  Scene scene_;
  InstrumentSet<MpmCuda> instruments_;
  double spacing_ = 0, rho_ = 0;
  size_t n_ = 0;
  // device: particles (e: volumetric strain J - 1), sort scratch, blocks, grid, walls
  thr::device_vector<T> x_[D], v_[D], C_[D * D], e_, vol_, held_, tag_, tmp_;  // tag_: solver/inflow.h
  thr::device_vector<int32_t> pblk_, pstart_, p_nbr_;
  thr::device_vector<uint32_t> order_;
  thr::device_vector<uint64_t> keys_, pkeys_, gkeys_, nbr_keys_;
  thr::device_vector<T> grid_;
  thr::device_vector<uint8_t> gwall_, ghost_axes_;
  thr::device_vector<int64_t> ghost_mirror_;
  thr::device_vector<T> ghost_dv_;    // D x nodes
  thr::device_vector<T> ghost_pool_;  // kGhostPoolLanes D x nodes
  thr::device_vector<int32_t> ghost_wall_;
  thr::device_vector<Wall<D, T>> walls_;
  thr::device_vector<double> impulse_;
  thr::device_vector<double> probe_geometry_, probe_push_d_;  // mpm::probe_geometry; per probe, the push
  std::vector<double> probe_push_;                            // its copy on the host, for the instruments
  thr::device_vector<double> fill_work_;
  int n_walls_ = 0;
  int has_sym_ = 0;  // a symmetry plane (mpm::SymmetryPlane)
  mpm::SymmetryPlane sym_;
  mpm::Container<D, T> container_;  // the domain box
  bool has_loads_ = false;
  // debris (the boxes on the host; their views, each box's band and the particles it pushed out on the device)
  std::unique_ptr<DebrisCoupling> debris_;
  thr::device_vector<RigidBoxView> box_views_;
  thr::device_vector<double> box_radius_, push_share_;
  thr::device_vector<int32_t> node_body_, particle_body_, push_body_, push_block_;
  thr::device_vector<int64_t> picked_;
  thr::device_vector<CouplingNode> coupling_;
  std::vector<CouplingNode> h_coupling_;
  // host
  std::unique_ptr<InflowBoundary<D, T>> inflow_;
  struct {
    std::vector<T> x[D], v[D], C[D * D], e, vol, held, tag;
  } h_;  // the particles on the host, for the inflow
  mutable std::vector<T> hx_[D], hv_[D], hvol_;
  mutable bool host_fresh_ = false, host_vol_fresh_ = false;
  std::vector<double> load_impulse_;
  bool needs_sort_ = true;
  RunState run_;  // the clock, the audit's budget, the status (run_state.h)
};

std::unique_ptr<Simulation> make(const Scene& scene, const SimulationOptions& options) {
  const bool f = scene.solver.precision == Precision::kFloat;
  if (scene.dimension == 2) {
    if (f) return std::make_unique<MpmCuda<2, float>>(scene, options);
    return std::make_unique<MpmCuda<2, double>>(scene, options);
  }
  if (f) return std::make_unique<MpmCuda<3, float>>(scene, options);
  return std::make_unique<MpmCuda<3, double>>(scene, options);
}

}  // namespace
}  // namespace mpm

#ifdef FLUME_CUDA_EMULATION
std::unique_ptr<Simulation> make_cuda_host_emulation(const Scene& scene, const SimulationOptions& options) {
  return mpm::make(scene, options);
}
#else
std::unique_ptr<Simulation> make_cuda_simulation(const Scene& scene, const SimulationOptions& options) {
  return mpm::make(scene, options);
}

bool cuda_device_present() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    cudaGetLastError();  // clear the sticky error: no driver or no device is an answer, not a failure
    return false;
  }
  return count > 0;
}
#endif

}  // namespace flume
