// The CPU backend's four solvers: D in {2, 3} x T in {float, double}. Each file of solver/mpm/cpu_*.cpp
// instantiates what it defines for all four with FLUME_MPM_CPU_VARIANTS(X), X(D, T) one instantiation.
#pragma once

#define FLUME_MPM_CPU_VARIANTS(X) X(2, float) X(2, double) X(3, float) X(3, double)
