#include "solver/simulation.h"

#include "common/errors.h"
#include "solver/checkpoint.h"
#include "solver/cpu_kernels.h"

namespace flume {

#ifdef FLUME_HAVE_CUDA
std::unique_ptr<Simulation> make_cuda_simulation(const Scene& scene, const SimulationOptions& options);
bool cuda_device_present();
#endif

void Simulation::checkpoint(StateArchive& ar) {
  throw InputError(ar.file().empty() ? std::string("--checkpoint-every") : ar.file(), "backend",
                   "this backend does not checkpoint yet: run with --backend cpu");
}

void checkpoint_state(StateArchive& ar, TimeSeries& s) {
  ar(s.components);
  ar(s.time);
  ar(s.values);
}

void checkpoint_state(StateArchive& ar, SectionSeries& s) {
  ar(s.x_m);
  ar(s.floor_m);
  ar(s.bin_width_m);
  ar(s.y);
  ar(s.time);
  ar(s.depth);
  ar(s.velocity);
  ar(s.z);
  ar(s.profile);
}

void checkpoint_state(StateArchive& ar, Record& r) {
  ar.section("record");
  ar(r.gauges);
  ar(r.probes);
  ar(r.loads);
  ar(r.pressures);
  ar(r.sections);
  ar(r.diagnostics);
}

bool cuda_available() {
#ifdef FLUME_HAVE_CUDA
  return cuda_device_present();
#else
  return false;
#endif
}

std::unique_ptr<Simulation> make_simulation(const Scene& scene, const SimulationOptions& options) {
  if (scene.solver.method == SolverMethod::kSph) {
    if (options.backend == Backend::kCuda)
      throw InputError("--backend", "cuda", "SPH runs on the CPU only yet (solver.method sph): run with --backend cpu");
    return make_sph_simulation(scene, options);
  }
  if (options.backend == Backend::kCuda) {
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
