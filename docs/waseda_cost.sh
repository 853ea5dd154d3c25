#!/usr/bin/env bash
# Issue 3 item 5: the cost of each variant at dx 0.02 and 0.01 m, measured on short runs (docs/waseda.md, the
# table "Item 5's table"). 2D: 0.5 s simulated; 3D: flume bench from the start (10 steps, 3 at 0.01 m).
#   docs/waseda_cost.sh [FLUME] [OUT]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flume=${1:-$root/build/bin/flume}
out=${2:-$(mktemp -d)}
mkdir -p "$out"
for dx in 0.02 0.01; do
  "$flume" run "$root/scenes/waseda/waseda_2d.json" --out "$out/2d_$dx" --threads 2 --set solver.dx=$dx \
    --set solver.end_time=0.5 >/dev/null
  echo "waseda_2d dx $dx: $(jq -c .cost "$out/2d_$dx/run.json")"
done
for v in waseda_3d_half waseda_3d; do
  for dx in 0.02 0.01; do
    n=10
    [[ $dx == 0.01 ]] && n=3
    echo "$v dx $dx: $("$flume" bench "$root/scenes/waseda/$v.json" --steps $n --threads 2 --set solver.dx=$dx | jq -c 'del(.scene)')"
  done
done
