// Which instruction set the CPU solvers' loops run with. The default build is portable (the x86-64 baseline,
// SSE2: one binary for every node of a cluster), and its hot loops would leave most of a newer CPU's vector
// units idle. So the CPU backends (MPM's solver/mpm/cpu_*.cpp, SPH's solver/sph/sph_solver.cpp) are compiled a
// second time for AVX2 (solver/CMakeLists.txt) and each run takes the copy its CPU can execute. The copy is the
// same source with the same operations in the same order: no fused multiply-add (-ffp-contract=off) and Eigen's
// alignment kept at the baseline's 16 bytes, so both copies give the same numbers to the bit
// (`CpuKernels.*` tests); AVX2 only lets the vector loops take twice as many lanes at once.
//
// The AVX2 copy is linked as one object whose symbols are all local but its two factories
// (make_cpu_simulation_avx2, make_sph_simulation_avx2): none of its inline functions or template instances,
// compiled for AVX2, can stand in for the baseline's at link time, so a CPU without AVX2 never meets an AVX2
// instruction. Native builds (FLUME_NATIVE) and other compilers and CPUs have no copy.
#pragma once
#include <memory>

#include "solver/simulation.h"

// The name of a backend's factory in the copy being compiled: NAME_portable, or NAME_avx2 in the AVX2 copy.
#ifdef FLUME_CPU_KERNELS_AVX2
#define FLUME_KERNELS_ENTRY(name) name##_avx2
#else
#define FLUME_KERNELS_ENTRY(name) name##_portable
#endif

namespace flume {

enum class CpuKernels { kPortable, kAvx2 };

// The copy this process runs: AVX2 where the binary has it and the CPU supports it, unless the environment
// variable FLUME_CPU_KERNELS is "portable" (for comparisons; "avx2" asks for AVX2 and fails where it cannot
// be had). Decided once per process.
CpuKernels cpu_kernels();
const char* cpu_kernels_name(CpuKernels kernels);  // "portable", "avx2"
bool avx2_kernels_built();                          // whether this binary holds the AVX2 copy
bool cpu_supports_avx2();                           // whether this CPU runs AVX2 (false off x86)

// The backends' factories, each in the copy cpu_kernels() names (solver/cpu_kernels.cpp dispatches).
std::unique_ptr<Simulation> make_cpu_simulation(const Scene& scene, const SimulationOptions& options);
std::unique_ptr<Simulation> make_sph_simulation(const Scene& scene, const SimulationOptions& options);

// Each copy's own factories (FLUME_KERNELS_ENTRY); the AVX2 ones are defined only where avx2_kernels_built().
std::unique_ptr<Simulation> make_cpu_simulation_portable(const Scene& scene, const SimulationOptions& options);
std::unique_ptr<Simulation> make_sph_simulation_portable(const Scene& scene, const SimulationOptions& options);
std::unique_ptr<Simulation> make_cpu_simulation_avx2(const Scene& scene, const SimulationOptions& options);
std::unique_ptr<Simulation> make_sph_simulation_avx2(const Scene& scene, const SimulationOptions& options);

}  // namespace flume
