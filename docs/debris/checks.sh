#!/usr/bin/env bash
# docs/debris.md, "Measured": the checks of issue 4 that couple water and boxes (test_debris: Floating.*, Coupling.*,
# Exchange.*, Metrics.*), run with their output (the numbers the table quotes), headed by the commit and the machine.
# test_rigid (Bullet alone: incline, drop, stack) has no water and is not run here.
#   docs/debris/checks.sh [BUILD]   (BUILD: a build with the tests, default build/; THREADS, default 1)
# Cost on the 2-core VM, one thread: a few minutes.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
build=$(realpath "${1:-$root/build}")
threads=${THREADS:-1}
measured_on "$build/bin/flume" "$threads"
echo
OMP_NUM_THREADS=$threads OMP_WAIT_POLICY=PASSIVE /usr/bin/time -f '(%e s wall, %U s user)' \
  "$build/bin/test_debris" --gtest_filter='Floating.*:Coupling.*:Exchange.*:Metrics.*' --gtest_brief=1 2>&1 |
  grep -v '^Running main' || true
