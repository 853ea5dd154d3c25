// Helpers for SPH's vector loops (fluid_pair_lanes.h, gather_lanes.h): the candidates of a neighbour search
// narrowed to those within the kernel's support, and per-neighbour slots summed in a fixed order. A loop over
// a list of neighbours with no branch in its body is what GCC vectorises (gathers where the CPU has them).
#pragma once
#include <algorithm>
#include <cstdint>

namespace flume::sph {

// The particles of one kind a point's sums run over: positions, velocities, density, 1/rho, pressure, mass.
template <int D, typename T>
struct NeighbourView {
  const T* x[D] = {};
  const T* v[D] = {};
  const T *rho = nullptr, *inv_rho = nullptr, *p = nullptr, *mass = nullptr;
};

// r = x - x_b and w = v - v_b for particle b of B; returns r . r.
template <int D, typename T>
inline T separation(const NeighbourView<D, T>& B, int b, const T* x, const T* v, T* r, T* w) {
  T r2 = 0;
  for (int d = 0; d < D; ++d) {
    r[d] = x[d] - B.x[d][b];
    w[d] = v[d] - B.v[d][b];
    r2 += r[d] * r[d];
  }
  return r2;
}

// Appends to nb[n ..] the particles of [b0, b1) (positions X, one array per axis) within the support of x:
// r^2 < support2, and r^2 > 0 with kSkipSelf (a particle's own position, whose terms are zero). The
// distances are taken kScan at once by a vector loop; flush() is called, and must empty the list, before it
// could overflow.
template <int D, typename T, bool kSkipSelf, int kList, class Flush>
void collect_within(const T* const (&X)[D], const T* x, T support2, uint32_t b0, uint32_t b1,
                    uint32_t (&nb)[kList], int& n, const Flush& flush) {
  constexpr int kScan = 32;
  static_assert(kScan <= kList, "a scan must fit in an empty list");
  for (uint32_t c = b0; c < b1; c += kScan) {
    const int nc = static_cast<int>(std::min<uint32_t>(kScan, b1 - c));
    T dist2[kScan];
    for (int l = 0; l < nc; ++l) {
      T r2 = 0;
      for (int d = 0; d < D; ++d) {
        const T r = x[d] - X[d][c + l];
        r2 += r * r;
      }
      dist2[l] = r2;
    }
    if (n + nc > kList) flush();
    for (int l = 0; l < nc; ++l) {
      nb[n] = c + l;
      n += dist2[l] < support2 && (!kSkipSelf || dist2[l] > T(0)) ? 1 : 0;
    }
  }
}

// The sum of s[0 .. n) in eight running sums added pairwise: a fixed order the compiler vectorises.
template <typename T, int N>
inline T lane_sum(const T (&s)[N], int n) {
  T part[8] = {};
  int l = 0;
  for (; l + 8 <= n; l += 8)
    for (int k = 0; k < 8; ++k) part[k] += s[l + k];
  for (int k = 0; l + k < n; ++k) part[k] += s[l + k];
  return ((part[0] + part[1]) + (part[2] + part[3])) + ((part[4] + part[5]) + (part[6] + part[7]));
}
template <typename T, int N>
inline T lane_max(const T (&s)[N], int n) {
  T m = T(0);
  for (int l = 0; l < n; ++l) m = s[l] > m ? s[l] : m;
  return m;
}

}  // namespace flume::sph
