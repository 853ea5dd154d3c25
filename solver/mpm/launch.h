// One launch for the step's per-particle and per-node bodies (the AMReX ParallelFor habit, STYLE.md):
// parallel_for(n, f) calls f(i) for i in [0, n). On a GPU it is a CUDA kernel (Thrust's for_each over a
// counting range launches one); the CUDA source compiled for the host (FLUME_CUDA_EMULATION) runs it through
// Thrust's sequential system; the CPU backend runs it as an OpenMP loop. The bodies are the same FLUME_HD
// functions.
//
// Each build of it lives in its own inline namespace, so that the CPU's and the emulated CUDA backend's,
// linked into one program, are different functions rather than one function defined twice.
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#if defined(__CUDACC__) || defined(FLUME_CUDA_EMULATION)
#include <thrust/execution_policy.h>
#include <thrust/for_each.h>
#include <thrust/iterator/counting_iterator.h>
#endif

namespace flume::mpm {

#if defined(__CUDACC__) || defined(FLUME_CUDA_EMULATION)
inline namespace launch_thrust {
template <typename F>
void parallel_for(size_t n, const F& f) {
  THRUST_NS_QUALIFIER::counting_iterator<size_t> first(0);
  THRUST_NS_QUALIFIER::for_each(THRUST_NS_QUALIFIER::device, first, first + n, f);
}

// Work on a tile of grid nodes per group (a particle block): f.load(g, v, tile) sets tile entry v (of
// f.tile_entries()), f.items(g, first, last) gives group g's items, f.item(g, i, tile) works item i against the
// tile (adding with mpm::accumulate, which is atomic on a device, or reading), f.flush(g, v, tile) moves entry v
// to where it belongs. The tile holds f.tile_values() values of type T. On a GPU a group is a thread block, its
// tile in shared memory and its threads striding over the items: a scatter's many adds into one node, or a
// gather's many reads of it, stay in shared memory, and each node crosses global memory once per group.
// Elsewhere each group runs serially.
#if defined(__CUDACC__) && !defined(FLUME_CUDA_EMULATION)
template <typename T, typename F>
__global__ void tiled_kernel(F f) {
  extern __shared__ unsigned char tile_bytes[];
  T* tile = reinterpret_cast<T*>(tile_bytes);
  const size_t g = blockIdx.x;
  for (int v = threadIdx.x; v < f.tile_entries(); v += blockDim.x) f.load(g, v, tile);
  __syncthreads();
  size_t first, last;
  f.items(g, first, last);
  for (size_t i = first + threadIdx.x; i < last; i += blockDim.x) f.item(g, i, tile);
  __syncthreads();
  for (int v = threadIdx.x; v < f.tile_entries(); v += blockDim.x) f.flush(g, v, tile);
}
template <typename T, typename F>
void tiled_for(size_t groups, const F& f) {
  if (groups == 0) return;
  constexpr int kThreads = 128;
  tiled_kernel<T, F><<<static_cast<unsigned>(groups), kThreads, f.tile_values() * sizeof(T)>>>(f);
  const cudaError_t e = cudaPeekAtLastError();
  if (e != cudaSuccess) throw std::runtime_error(std::string("CUDA tiled launch: ") + cudaGetErrorString(e));
}
#else
template <typename T, typename F>
void tiled_for(size_t groups, const F& f) {
  std::vector<T> tile(f.tile_values());
  for (size_t g = 0; g < groups; ++g) {
    for (int v = 0; v < f.tile_entries(); ++v) f.load(g, v, tile.data());
    size_t first, last;
    f.items(g, first, last);
    for (size_t i = first; i < last; ++i) f.item(g, i, tile.data());
    for (int v = 0; v < f.tile_entries(); ++v) f.flush(g, v, tile.data());
  }
}
#endif
}  // namespace launch_thrust
#else
inline namespace launch_openmp {
template <typename F>
void parallel_for(size_t n, const F& f) {
#pragma omp parallel for schedule(static)
  for (size_t i = 0; i < n; ++i) f(i);
}
}  // namespace launch_openmp
#endif

}  // namespace flume::mpm
