#!/usr/bin/env bash
# docs/waseda.md, "Half basin against the full basin": scenes/studies/waseda_half_vs_full.json (dx 0.05 m, 4 s) by
# docs/tradeoff/study.sh (its tables, headed by the commit and the machine), then the two runs' WG1 and WG2 in one
# figure, docs/waseda_half_vs_full.svg (FIG=0: into OUT instead).
#   docs/waseda/half_vs_full.sh [FLUME] [OUT]      THREADS (as study.sh)
# Cost on the 2-core VM, one thread: about 11 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-waseda_half_vs_full}")
"$root/docs/tradeoff/study.sh" "$root/scenes/studies/waseda_half_vs_full.json" "$flume" "$out"
dir() { sqlite3 "$out/study.sqlite" "select run_dir from runs where design_index = $1 and status = 'ok'"; }  # the spec's settings, in order
fig=$root/docs/waseda_half_vs_full.svg
[[ ${FIG:-1} == 1 ]] || fig=$out/waseda_half_vs_full.svg
"$flume" gauges "$(dir 0)=full basin" "$(dir 1)=half basin" \
  --gauges WG1,WG2 --title "waseda_3d against waseda_3d_half, dx 0.05 m" --out "$fig" >"$out/gauges.txt"
