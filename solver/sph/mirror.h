// A symmetry plane in SPH by the method of images: a particle within reach of the plane interacts with the
// mirror images of the fluid and wall particles on its side, as it would with their counterparts in the whole
// symmetric flow. The images are not stored: the pair sums are taken at the particle's own image (its position
// and velocity reflected) over the real particles, and the result is reflected back. A pair's terms are
// covariant under the reflection M (a fixed axis negated): r and v map as vectors, the sub-particle stress as
// M tau M, gravity as a vector (Params::g), and the scalars (density rates, step limits) are unchanged.
#pragma once
#include "common/host_device.h"
#include "solver/sph/sph_kernels.h"

namespace flume::sph {

// The plane axis = at; the modelled water lies on the side `sign` (+1: x[axis] >= at).
struct Mirror {
  int axis = -1;
  int sign = 1;
  double at = 0;
  bool active() const { return axis >= 0; }
  // Signed distance from the plane, positive on the water's side.
  template <typename T>
  double side(const T* x) const {
    return sign * (double(x[axis]) - at);
  }
};

template <int D, typename T>
FLUME_HD void reflect_point(int axis, T at, const T* x, T* out) {
  for (int d = 0; d < D; ++d) out[d] = x[d];
  out[axis] = T(2) * at - x[axis];
}
template <int D, typename T>
FLUME_HD void reflect_vector(int axis, const T* v, T* out) {
  for (int d = 0; d < D; ++d) out[d] = v[d];
  out[axis] = -v[axis];
}
// M tau M of a symmetric tensor in Sym<D> storage: the entries with exactly one index on the axis change sign.
template <int D, typename T>
FLUME_HD void reflect_sym(int axis, const T* tau, T* out) {
  for (int i = 0; i < D; ++i)
    for (int j = i; j < D; ++j) {
      const int k = Sym<D>::at(i, j);
      out[k] = ((i == axis) != (j == axis)) ? -tau[k] : tau[k];
    }
}

// Adds what a particle gathered at its image (in the reflected frame) to what it gathered itself.
template <int D, typename T>
FLUME_HD void add_reflected(int axis, const Accum<D, T>& m, Accum<D, T>& A) {
  for (int d = 0; d < D; ++d) {
    A.acc[d] += d == axis ? -m.acc[d] : m.acc[d];
    A.gradc[d] += d == axis ? -m.gradc[d] : m.gradc[d];
    for (int e = 0; e < D; ++e) {
      const T g = m.gradv[d * D + e];
      A.gradv[d * D + e] += ((d == axis) != (e == axis)) ? -g : g;
    }
  }
  A.drho += m.drho;
  A.divr += m.divr;
  A.visc_dt = m.visc_dt > A.visc_dt ? m.visc_dt : A.visc_dt;
  A.pairs += m.pairs;
}

}  // namespace flume::sph
