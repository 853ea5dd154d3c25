#include "solver/simulation.h"

#include "common/errors.h"

namespace flume {

std::unique_ptr<Simulation> make_cpu_simulation(const Scene& scene, const SimulationOptions& options);
#ifdef FLUME_HAVE_CUDA
std::unique_ptr<Simulation> make_cuda_simulation(const Scene& scene, const SimulationOptions& options);
bool cuda_device_present();
#endif

bool cuda_available() {
#ifdef FLUME_HAVE_CUDA
  return cuda_device_present();
#else
  return false;
#endif
}

std::unique_ptr<Simulation> make_simulation(const Scene& scene, const SimulationOptions& options) {
  if (options.backend == Backend::kCuda) {
    if (scene.debris.present)
      throw InputError(scene.file, "debris",
                       "the CUDA backend does not couple debris yet: run this scene with --backend cpu");
    if (scene.inflow.present)
      throw InputError(scene.file, "inflow", "the CUDA backend does not support inflow yet: run this scene with --backend cpu");
#ifdef FLUME_HAVE_CUDA
    if (!cuda_device_present()) throw InputError("--backend", "cuda", "no CUDA device is present on this machine");
    return make_cuda_simulation(scene, options);
#else
    throw InputError("--backend", "cuda", "this flume was built without CUDA (nvcc was not found at build time)");
#endif
  }
  return make_cpu_simulation(scene, options);
}

}  // namespace flume
