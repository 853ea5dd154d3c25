// The CPU backend's bookkeeping of the nodes near a symmetry plane (mpm::SymmetryPlane). A node within kZone
// cells of the plane on the modelled side, on it or beyond it is stored raw during the grid gather and
// updated after the fold; the particles stay on the modelled side, so only nodes one cell beyond it receive
// mass, and their mirrors lie within the zone. The grid blocks holding such nodes get a slot each, their raw
// nodes a dense entry (slot * kNodes + local): no list to gather or sort. (The CUDA backend folds node by
// node instead.)
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "solver/mpm/blocks_k.h"
#include "solver/mpm_kernels.h"

namespace flume::mpm {

template <int D>
long grid_index(const std::vector<uint64_t>& gkeys, const int* node) {
  return static_cast<long>(node_index<D>(gkeys.data(), gkeys.size(), node));
}

template <int D>
class SymmetryZone {
 public:
  static constexpr int kZone = 3;
  static constexpr int kNodes = Pow<D>::of(kBlock);

  explicit SymmetryZone(const SymmetryPlane& plane = {}) : sym_(plane) {}
  const SymmetryPlane& plane() const { return sym_; }

  bool in_zone(int i) const {
    return symmetry_side(sym_, i) >= 0 || std::abs(2 * i - sym_.twice) <= 2 * kZone;
  }

  // The slots, from the grid blocks (rebuilt with them).
  void index(const std::vector<uint64_t>& gkeys) {
    slot_.assign(gkeys.size(), -1);
    blocks_.clear();
    for (long g = 0; g < static_cast<long>(gkeys.size()); ++g) {
      int blk[D];
      unpack_key<D>(gkeys[g], blk);
      bool touches = false;
      for (int l = 0; l < kBlock && !touches; ++l) touches = in_zone(blk[sym_.axis] * kBlock + l);
      if (!touches) continue;
      slot_[g] = static_cast<int>(blocks_.size());
      blocks_.push_back(g);
    }
  }
  size_t entries() const { return blocks_.size() * kNodes; }
  int slot(long g) const { return slot_[g]; }
  long block(long q) const { return blocks_[q / kNodes]; }

  // Raw entry q: its grid block, returned, and its node coordinates.
  long node(long q, const std::vector<uint64_t>& gkeys, int* node) const {
    const long g = blocks_[q / kNodes];
    int blk[D];
    unpack_key<D>(gkeys[g], blk);
    for (int d = D - 1, r = static_cast<int>(q % kNodes); d >= 0; --d, r /= kBlock)
      node[d] = blk[d] * kBlock + r % kBlock;
    return g;
  }

  // The raw entry of a node's mirror across the plane, or -1 where the mirror is outside the zone or no
  // active block holds it.
  long mirror_entry(const int* node, const std::vector<uint64_t>& gkeys) const {
    int mirror[D];
    for (int d = 0; d < D; ++d) mirror[d] = node[d];
    mirror[sym_.axis] = sym_.twice - node[sym_.axis];
    if (!in_zone(mirror[sym_.axis])) return -1;
    const long gi = grid_index<D>(gkeys, mirror);
    if (gi < 0) return -1;
    const int s = slot_[gi / kNodes];
    return s >= 0 ? static_cast<long>(s) * kNodes + gi % kNodes : -1;
  }

 private:
  SymmetryPlane sym_;
  std::vector<int> slot_;     // per grid block: its slot among the blocks near the plane, or -1
  std::vector<long> blocks_;  // per slot: the grid block
};

}  // namespace flume::mpm
