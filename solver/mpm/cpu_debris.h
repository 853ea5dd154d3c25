// The CPU backend's side of the debris coupling (solver/debris_coupling.h holds the bodies and the implicit
// exchange; solver/mpm/debris_k.h the per-node and per-particle tests both backends share). The grid update
// lists, per thread, the nodes in or near a box; the exchange takes them in grid order, so the sums do not
// depend on the thread count. G2P pushes particles that entered a box back out and collects the momentum they
// lose per particle block, summed in block order afterwards. Header-only: its tests run inside the stage
// loops.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "solver/debris_coupling.h"
#include "solver/mpm/blocks_k.h"
#include "solver/mpm/debris_k.h"
#include "solver/mpm_kernels.h"

namespace flume::mpm {

template <int D, typename T>
class CpuDebris {
 public:
  explicit CpuDebris(const Scene& scene) : bodies_(scene) {}
  DebrisCoupling& bodies() { return bodies_; }
  const DebrisCoupling& bodies() const { return bodies_; }

  // --- grid update ---
  void begin_grid(int nthreads) { coupling_.assign(nthreads, {}); }
  std::vector<CouplingNode>* thread_nodes(int thread) { return &coupling_[thread]; }

  // Whether a box can reach the nodes of grid block `blk`.
  bool near_grid_block(const int* blk, const double* grid_lo, double dx) const {
    double centre[3] = {0, 0, 0}, half_diag2 = 0;
    for (int d = 0; d < D; ++d) {
      centre[d] = grid_lo[d] + (blk[d] * kBlock + 0.5 * (kBlock - 1)) * dx;
      half_diag2 += 0.25 * ((kBlock - 1) * dx) * ((kBlock - 1) * dx);
    }
    const auto& views = bodies_.views();
    bool near = false;
    for (int b = 0; b < int(views.size()) && !near; ++b) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (centre[d] - views[b].centre[d]) * (centre[d] - views[b].centre[d]);
      const double reach = std::sqrt(half_diag2) + bodies_.bounding_radius(b) + dx;
      near = r2 <= reach * reach;
    }
    return near;
  }

  // A node at xn is a moving-wall node of the box it lies in (or within the band of): listed in `nodes`, its
  // velocity set after every node is known, by the implicit exchange (couple).
  bool add_node(const double* xn, double dx, size_t idx, T m, T e_node, const T* v,
                const TaitLaw<double>& law_d, const T* strain_slope, std::vector<CouplingNode>* nodes) const {
    CouplingNode c;
    const auto& views = bodies_.views();
    if (!coupling_node<D, T>(views.data(), bodies_.bounding_radii().data(), int(views.size()), xn, kCouplingBandCells * dx,
                             idx, m, e_node, v, law_d, strain_slope, c))
      return false;
    nodes->push_back(c);
    return true;
  }

  // The exchange: the listed nodes in grid order, solved together with the boxes' motion; then the boxes step
  // by dt and the nodes take their projected velocities.
  void couple(std::vector<T>* gv, double dt) {
    std::vector<CouplingNode> nodes;
    for (auto& part : coupling_) nodes.insert(nodes.end(), part.begin(), part.end());
    std::sort(nodes.begin(), nodes.end(),
              [](const CouplingNode& a, const CouplingNode& b) { return a.id < b.id; });
    bodies_.exchange(nodes, dt);
    for (const auto& c : nodes)
      for (int d = 0; d < D; ++d) gv[d][c.id] = T(c.v[d]);
  }

  // --- G2P ---
  // Only the blocks near a box can push particles out: they zero their own slots in the loop and are flagged,
  // and only they are summed after it (a block far from every box would add exact zeros), instead of zeroing
  // and summing every block's slots serially each step.
  void begin_g2p(long nblocks) {
    const int nbodies = bodies_.body_count();
    push_out_.resize(static_cast<size_t>(nblocks) * nbodies * 6);
    push_near_.assign(static_cast<size_t>(nblocks), 0);
  }
  // Whether a box may come within `margin` of the particles of block `key` (a particle may sit up to one cell
  // outside its block).
  bool near_particle_block(uint64_t key, double margin, const double* grid_lo, double dx) const {
    int blk[D];
    unpack_key<D>(key, blk);
    double centre[3] = {0, 0, 0}, half_diag2 = 0;
    for (int d = 0; d < D; ++d) {
      centre[d] = grid_lo[d] + (blk[d] * kBlock + 0.5 * kBlock) * dx;
      half_diag2 += 0.25 * ((kBlock + 2) * dx) * ((kBlock + 2) * dx);
    }
    const auto& views = bodies_.views();
    for (int b = 0; b < int(views.size()); ++b) {
      double r2 = 0;
      for (int d = 0; d < 3; ++d) r2 += (centre[d] - views[b].centre[d]) * (centre[d] - views[b].centre[d]);
      const double reach = std::sqrt(half_diag2) + bodies_.bounding_radius(b) + margin;
      if (r2 <= reach * reach) return true;
    }
    return false;
  }
  // Block p's slots (6 per box: impulse, then moment about the origin), zeroed; the block is flagged as near.
  double* block_slots(long p) {
    const int nbodies = bodies_.body_count();
    push_near_[p] = 1;
    double* slots = &push_out_[static_cast<size_t>(p) * nbodies * 6];
    std::fill_n(slots, nbodies * 6, 0.0);
    return slots;
  }
  // A particle inside a box goes back to its surface, without the velocity that approached it; the momentum
  // it loses is added to its block's slots for that box.
  void push_out(std::vector<T>* x, std::vector<T>* v, double mass, size_t i, double* slots) const {
    double xp[3] = {0, 0, 0}, vp[3] = {0, 0, 0}, share[6];
    for (int d = 0; d < D; ++d) {
      xp[d] = x[d][i];
      vp[d] = v[d][i];
    }
    const auto& views = bodies_.views();
    const int b = push_out_of_box(views.data(), bodies_.bounding_radii().data(), int(views.size()), mass, xp,
                                  vp, share);
    if (b < 0) return;
    for (int d = 0; d < D; ++d) {
      x[d][i] = T(xp[d]);
      v[d][i] = T(vp[d]);
    }
    for (int k = 0; k < 6; ++k) slots[b * 6 + k] += share[k];
  }
  // The particles' lost momentum goes to the boxes, summed in block order (thread-independent).
  void end_g2p(long nblocks) {
    const int nbodies = bodies_.body_count();
    for (int b = 0; b < nbodies; ++b) {
      double J[3] = {0, 0, 0}, L[3] = {0, 0, 0};
      for (long p = 0; p < nblocks; ++p) {
        if (!push_near_[p]) continue;
        for (int d = 0; d < 3; ++d) {
          J[d] += push_out_[(static_cast<size_t>(p) * nbodies + b) * 6 + d];
          L[d] += push_out_[(static_cast<size_t>(p) * nbodies + b) * 6 + 3 + d];
        }
      }
      bodies_.add_particle_impulse(b, J, L);
    }
  }

 private:
  DebrisCoupling bodies_;
  std::vector<std::vector<CouplingNode>> coupling_;  // per thread: the nodes found in boxes this step
  std::vector<double> push_out_;  // per particle block and box: impulse and moment of pushed-out particles
  std::vector<uint8_t>
      push_near_;  // per particle block: whether it is near a box (its push_out_ slots are set)
};

}  // namespace flume::mpm
