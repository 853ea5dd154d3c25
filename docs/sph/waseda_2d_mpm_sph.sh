#!/usr/bin/env bash
# Issue 24 item 3: waseda_2d with MPM and SPH at two resolutions each (6 s, float, one thread per run), the four
# gauges overlaid in docs/sph/waseda_2d_mpm_sph.svg with each run's peaks and arrivals (`flume gauges`), and
# each run's particles, steps and CPU time.
# Usage: docs/sph/waseda_2d_mpm_sph.sh [FLUME] [OUT]
set -euo pipefail
flume=${1:-build/bin/flume}; out=${2:-waseda-2d-mpm-sph}
mkdir -p "$out"
scene=scenes/waseda/waseda_2d.json
runs=()
for run in mpm:0.02 mpm:0.01 sph:0.04 sph:0.02; do
  method=${run%%:*}; dx=${run##*:}; dir="$out/${method}_$dx"
  [ -f "$dir/run.json" ] || /usr/bin/time -f "%U" -o "$dir.cpu" env OMP_NUM_THREADS=1 "$flume" run "$scene" \
    --out "$dir" --set solver.method="$method" --set solver.dx="$dx" --set solver.end_time=6 -q
  echo "$method dx $dx: $(grep -o '"particles": [0-9]*\|"steps": [0-9]*' "$dir/run.json" | tr '\n' ' ')CPU $(cat "$dir.cpu" 2>/dev/null || echo '?') s"
  runs+=("$dir=${method^^} dx $dx")
done
"$flume" gauges "${runs[@]}" --out docs/sph/waseda_2d_mpm_sph.svg --title "waseda_2d: MPM and SPH ($(git rev-parse --short HEAD), float)"
