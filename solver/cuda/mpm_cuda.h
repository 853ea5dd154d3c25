// Entry points of the CUDA backend (solver/cuda/mpm_cuda.cu). simulation.cpp declares the first two itself;
// this header is for tests.
#pragma once
#include <memory>

#include "solver/simulation.h"

namespace flume {

#ifdef FLUME_HAVE_CUDA
std::unique_ptr<Simulation> make_cuda_simulation(const Scene& scene, const SimulationOptions& options);
bool cuda_device_present();  // false, without an error, on a machine with no device or no driver
#endif

// The same source compiled by the host compiler with Thrust's sequential C++ back end
// (mpm_cuda_emulated.cpp): every algorithm, index computation and formula of the CUDA backend, run on the
// CPU, so that a machine with no GPU still checks them against the CPU solver. Not a product backend: it is
// single-threaded.
std::unique_ptr<Simulation> make_cuda_host_emulation(const Scene& scene, const SimulationOptions& options);

}  // namespace flume
