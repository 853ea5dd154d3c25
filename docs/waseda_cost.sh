#!/usr/bin/env bash
# Issue 3 item 5: the cost of each variant at dx 0.02 and 0.01 m, measured on short runs (docs/waseda.md, the
# table "Item 5's table"). 2D: 0.5 s simulated; 3D: flume bench from the start (10 steps, 3 at 0.01 m).
#   docs/waseda_cost.sh [FLUME] [OUT]      THREADS (2), DXS ("0.02 0.01")
# Cost on the 2-core VM: about 5 min on one thread (the 3D benches at 0.01 m seed 21.7M and 43.3M particles, 6 GB).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/docs/measured_on.sh"
flume=${1:-$root/build/bin/flume}
out=${2:-$(mktemp -d)}
threads=${THREADS:-2}
dxs=${DXS:-0.02 0.01}
mkdir -p "$out"
measured_on "$flume" "$threads"
for dx in $dxs; do
  "$flume" run "$root/scenes/waseda/waseda_2d.json" --out "$out/2d_$dx" --threads "$threads" --set solver.dx=$dx \
    --set solver.end_time=0.5 >/dev/null
  echo "waseda_2d dx $dx: $(jq -c .cost "$out/2d_$dx/run.json")"
done
for v in waseda_3d_half waseda_3d; do
  for dx in $dxs; do
    n=10
    [[ $dx == 0.01 ]] && n=3
    echo "$v dx $dx: $("$flume" bench "$root/scenes/waseda/$v.json" --steps $n --threads "$threads" --set solver.dx=$dx | jq -c 'del(.scene)')"
  done
done
