#!/usr/bin/env bash
# docs/debris.md, "The demo" paragraph: scenes/waseda/waseda_strip.json as shipped (dx 0.05 m, 6 s, three upstream
# containers, the scene's nominal contact coefficients), its debris metrics and cost, headed by the commit and the
# machine. (The demo's own 8 runs over the coefficients: ./scripts/demo, docs/surrogates.md "The demo".)
#   docs/debris/strip.sh [FLUME] [OUT]     THREADS (1)
# Cost on the 2-core VM, one thread: about 1-2 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-waseda-strip}")
threads=${THREADS:-1}
run_scene_once "$flume" "$root/scenes/waseda/waseda_strip.json" "$out" "$threads"
echo "| debris | longitudinal max (m) | at (s) | lateral at run-up (m) | spreading at run-up (deg) | speed at 6 s (m/s) | at rest |"
echo "|---|---|---|---|---|---|---|"
for d in D1 D2 D3; do
  jq -r --arg d "$d" '.metrics as $m | [$m[$d + ".longitudinal_max_m"], $m[$d + ".runup_time_s"],
      $m[$d + ".lateral_runup_m"], $m[$d + ".spreading_runup_deg"], $m[$d + ".final_speed_m_s"],
      $m[$d + ".at_rest"]] | @tsv' "$out/run.json" |
    awk -F'\t' -v d="$d" '{ printf "| %s | %.3f | %.2f | %.3f | %.2f | %.3f | %s |\n", d, $1, $2, $3, $4, $5, ($6 == 1 ? "yes" : "no") }'
done
