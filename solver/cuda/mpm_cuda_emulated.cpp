// The CUDA backend's source compiled by the host compiler against Thrust's sequential C++ system: see
// make_cuda_host_emulation in mpm_cuda.h. Thrust and CUB are wrapped in their own namespace here so that
// their host-system instantiations cannot collide with the CUDA ones linked into the same program.
#define FLUME_CUDA_EMULATION 1
#define THRUST_DEVICE_SYSTEM THRUST_DEVICE_SYSTEM_CPP
#define THRUST_CUB_WRAPPED_NAMESPACE flume_cuda_emulation
#include "solver/cuda/mpm_cuda.cu"
