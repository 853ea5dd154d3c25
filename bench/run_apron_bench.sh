#!/usr/bin/env bash
# Solver speed on a thin sheet flow: the Waseda apron with six containers and the 5x2 columns at dx 0.02 m,
# resumed from a checkpoint of `docs/debris_waseda_apron.sh feed 5x2` (its apron_5x2/checkpoint.bin, taken
# while the bore runs over the apron) up to END seconds of simulated time, once per flume binary given.
# Prints, per binary, the step it reaches, the wall seconds of the whole command (the checkpoint's read and the
# final write included), and whether its result.h5 equals the first binary's (h5diff; the load cells' and the
# energies' OpenMP sums may differ by round-off with more than one thread, tests/solver/test_threads.cpp).
#
#   bench/run_apron_bench.sh CHECKPOINT FEED_RESULT_H5 END THREADS FLUME [FLUME ...]
#
# FEED_RESULT_H5 is the feed run's result.h5 that the checkpointed run was started with (feed2d/result.h5).
# Measure with nothing else running; the binaries run one after the other.
set -euo pipefail
[[ $# -ge 5 ]] || { sed -n 2,12p "$0" >&2; exit 2; }
ckpt=$1 feed=$2 end=$3 threads=$4
shift 4
root=$(cd "$(dirname "$0")/.." && pwd)
[[ -f $ckpt ]] || { echo "run_apron_bench.sh: no checkpoint at $ckpt" >&2; exit 2; }
[[ -f $feed ]] || { echo "run_apron_bench.sh: no feed record at $feed" >&2; exit 2; }
out=$(mktemp -d)
echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
first=""
k=0
for flume in "$@"; do
  k=$((k + 1))
  dir=$out/run$k
  mkdir -p "$dir"
  echo "# $flume: $("$flume" --version) (the default build is portable; -DFLUME_NATIVE=ON for native)"
  cp "$ckpt" "$dir/checkpoint.bin"
  start=$(date +%s.%N)
  "$flume" run "$root/scenes/waseda/waseda_apron.json" --out "$dir" --set solver.dx=0.02 --set solver.end_time="$end" \
    --set inflow.record="$feed" --set debris.count=6 --set debris.layers=2 --set debris.placement=upstream \
    --set obstacles.layout=5x2 --threads "$threads" --resume >"$dir/log.txt" 2>&1
  wall=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  steps=$(jq '.cost.steps' "$dir/run.json")
  same="-"
  if [[ -n $first ]]; then
    if h5diff -q "$first" "$dir/result.h5" >/dev/null 2>&1; then same="identical"; else
      same="differs in: $( (h5diff "$first" "$dir/result.h5" 2>/dev/null || true) | sed -n 's/^dataset: <\([^>]*\)>.*/\1/p' | sort -u | tr '\n' ' ')"
    fi
  else
    first=$dir/result.h5
  fi
  echo "$flume: $(head -1 "$dir/log.txt"); to t = $end s (step $steps), $threads threads, wall $wall s; result.h5 vs the first: $same"
done
rm -rf "$out"
