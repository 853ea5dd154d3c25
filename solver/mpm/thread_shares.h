// The CPU backend's split of the work among threads: one contiguous share of the particle blocks per thread,
// balanced by particle count, and the share of the grid blocks over the same keys. P2G, the grid update and
// G2P all hand share s to thread s, the same shares every step until the next sort, so each thread finds in
// its own cache what it wrote the stage before: its tiles in the grid gather, its nodes in G2P. Dynamic
// schedules handed half of each to the other core, and on two cores the grid update took longer than on one
// (docs/solver.md, "Thread shares").
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

namespace flume::mpm {

struct ThreadShares {
  // Share s: particle blocks [pfirst[s], pfirst[s + 1]), grid blocks [gfirst[s], gfirst[s + 1]).
  std::vector<long> pfirst, gfirst;

  int count() const { return static_cast<int>(pfirst.size()) - 1; }

  // pstart: the particle blocks' ranges (pstart.size() = blocks + 1); pkeys, gkeys: the sorted block keys.
  void split(const std::vector<uint32_t>& pstart, const std::vector<uint64_t>& pkeys,
             const std::vector<uint64_t>& gkeys, int shares) {
    shares = std::max(1, shares);
    const long np = static_cast<long>(pkeys.size());
    const double particles = pstart.empty() ? 0.0 : double(pstart.back());
    pfirst.assign(static_cast<size_t>(shares) + 1, np);
    gfirst.assign(static_cast<size_t>(shares) + 1, static_cast<long>(gkeys.size()));
    pfirst[0] = gfirst[0] = 0;
    for (int s = 1; s < shares; ++s) {
      // The first block that starts at or after this share's first particle.
      const auto target = static_cast<uint32_t>(particles * s / shares);
      const auto it = std::lower_bound(pstart.begin(), pstart.begin() + np, target);
      pfirst[s] = std::max(pfirst[s - 1], static_cast<long>(it - pstart.begin()));
      const uint64_t key = pfirst[s] < np ? pkeys[pfirst[s]] : UINT64_MAX;
      gfirst[s] =
          std::max(gfirst[s - 1],
                   static_cast<long>(std::lower_bound(gkeys.begin(), gkeys.end(), key) - gkeys.begin()));
    }
  }
};

}  // namespace flume::mpm
