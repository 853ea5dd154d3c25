// The CPU backend's variants: D in {2, 3} x T in {float, double}. Each file of solver/mpm/cpu_*.cpp
// instantiates what it defines for all of them with FLUME_MPM_CPU_VARIANTS(X), X(D, T) one instantiation.
#pragma once

#define FLUME_MPM_CPU_VARIANTS(X) X(2, float) X(2, double) X(3, float) X(3, double)

// MpmSolver's: each as APIC and as FLIP (MpmSolver::kFlipChannels), X(D, T, Flip).
#define FLUME_MPM_SOLVER_VARIANTS(X)                                                               \
  X(2, float, false) X(2, double, false) X(3, float, false) X(3, double, false) X(2, float, true) \
      X(2, double, true) X(3, float, true) X(3, double, true)
