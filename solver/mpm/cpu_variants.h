// The CPU backend's variants: D in {2, 3} x T in {float, double}. Each file of solver/mpm/cpu_*.cpp
// instantiates what it defines for all four with FLUME_MPM_CPU_VARIANTS(X), X(D, T) one instantiation.
#pragma once

#define FLUME_MPM_CPU_VARIANTS(X) X(2, float) X(2, double) X(3, float) X(3, double)

// MpmSolver's: each with the SIMD lanes a grid node's channels take (MpmSolver::kLanes), 8, and in 3D also 16
// for FLIP's old velocity (MpmSolver::kFlipChannels), X(D, T, Lanes).
#define FLUME_MPM_SOLVER_VARIANTS(X) \
  X(2, float, 8) X(2, double, 8) X(3, float, 8) X(3, double, 8) X(3, float, 16) X(3, double, 16)
