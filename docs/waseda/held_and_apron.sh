#!/usr/bin/env bash
# docs/waseda.md, "Held reservoir" and "The apron variant": the tests that measure them, run with their output
# (the numbers the tables quote), headed by the commit and the machine.
#   Waseda.HeldReservoirStaysPut  waseda_2d at dx 0.02 m held (f = 1) for 2 s: WG1-WG4's range, the RMS speed
#   Apron.*                       section and inflow checks; waseda_apron_2d fed by waseda_2d at dx 0.02 m, 5 s:
#                                 WG3 and WG4 RMS difference over 0-5 s and 2-5 s, cost ratios
#   docs/waseda/held_and_apron.sh [BUILD]   (BUILD: a build with the tests, default build/; THREADS, default 1)
# Cost on the 2-core VM, one thread: about 2 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
build=$(realpath "${1:-$root/build}")
threads=${THREADS:-1}
measured_on "$build/bin/flume" "$threads"
echo
for t in "test_waseda Waseda.HeldReservoirStaysPut" "test_apron Apron.*"; do
  bin=${t%% *} filter=${t#* }
  echo "== $bin --gtest_filter=$filter"
  OMP_NUM_THREADS=$threads OMP_WAIT_POLICY=PASSIVE /usr/bin/time -f '(%e s wall, %U s user)' \
    "$build/bin/$bin" --gtest_filter="$filter" --gtest_brief=1 2>&1 | grep -v '^\[' || true
done
