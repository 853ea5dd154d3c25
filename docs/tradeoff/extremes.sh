#!/usr/bin/env bash
# docs/tradeoff.md, "The extreme-value suite": runs test_extremes (every case of its table, one after another,
# each `flume run` in a child process) and prints the outcome table, headed by the commit and the machine.
#   docs/tradeoff/extremes.sh [BUILD]   (BUILD: a build with the tests, default build/)
# Cost on the 2-core VM: about 40 s.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
build=$(realpath "${1:-$root/build}")
measured_on "$build/bin/flume" 1
echo
out=$build/tests/study/extreme
rm -rf "$out"
OMP_WAIT_POLICY=PASSIVE "$build/bin/test_extremes" --gtest_brief=1 >"$build/extremes.log" 2>&1 || {
  tail -20 "$build/extremes.log"; exit 1; }
echo "| case | status | wall s | steps | particles | energy rise | message |"
echo "|---|---|---|---|---|---|---|"
# In the suite's order (its table of cases), not the folders' alphabetical one.
for d in $("$build/bin/test_extremes" --gtest_list_tests | sed -n 's/.*# GetParam() = //p'); do
  cat "$out/$d/outcome.md"
done
