#include "solver/cpu_kernels.h"

#include <cstdlib>
#include <string>

#include "common/errors.h"

namespace flume {

bool avx2_kernels_built() {
#ifdef FLUME_HAVE_AVX2_KERNELS
  return true;
#else
  return false;
#endif
}

bool cpu_supports_avx2() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

namespace {

bool avx2_available() { return avx2_kernels_built() && cpu_supports_avx2(); }

CpuKernels choose() {
  const char* asked = std::getenv("FLUME_CPU_KERNELS");
  const std::string want = asked ? asked : "";
  if (want == "portable") return CpuKernels::kPortable;
  if (want == "avx2") {
    if (!avx2_available())
      throw InputError("FLUME_CPU_KERNELS", "avx2",
                       avx2_kernels_built() ? "this CPU has no AVX2: unset it or set it to portable"
                                            : "this flume has no AVX2 copy (a native build, or not GCC on x86-64)");
    return CpuKernels::kAvx2;
  }
  if (!want.empty())
    throw InputError("FLUME_CPU_KERNELS", want, "allowed: portable, avx2, or unset for the best the CPU has");
  return avx2_available() ? CpuKernels::kAvx2 : CpuKernels::kPortable;
}

}  // namespace

CpuKernels cpu_kernels() {
  static const CpuKernels chosen = choose();
  return chosen;
}

const char* cpu_kernels_name(CpuKernels kernels) { return kernels == CpuKernels::kAvx2 ? "avx2" : "portable"; }

std::unique_ptr<Simulation> make_cpu_simulation(const Scene& scene, const SimulationOptions& options) {
#ifdef FLUME_HAVE_AVX2_KERNELS
  if (cpu_kernels() == CpuKernels::kAvx2) return make_cpu_simulation_avx2(scene, options);
#endif
  return make_cpu_simulation_portable(scene, options);
}

std::unique_ptr<Simulation> make_sph_simulation(const Scene& scene, const SimulationOptions& options) {
#ifdef FLUME_HAVE_AVX2_KERNELS
  if (cpu_kernels() == CpuKernels::kAvx2) return make_sph_simulation_avx2(scene, options);
#endif
  return make_sph_simulation_portable(scene, options);
}

}  // namespace flume
