#!/usr/bin/env bash
# docs/debris.md, "End to end" (and README's cost line): scenes/debris/bore_container.json as shipped (dx 0.015 m,
# 2 s), its debris metrics and cost, headed by the commit and the machine.
#   docs/debris/bore_container.sh [FLUME] [OUT]     THREADS (1)
# Cost on the 2-core VM, one thread: about 1-2 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-bore-container}")
threads=${THREADS:-1}
run_scene_once "$flume" "$root/scenes/debris/bore_container.json" "$out" "$threads"
echo "| debris | run-up (m) | at (s) | longitudinal at 2 s (m) | lateral at 2 s (m) | speed at 2 s (m/s) | accelerometer native / 30 Hz (N) |"
echo "|---|---|---|---|---|---|---|"
for d in D1 D2; do
  jq -r --arg d "$d" '.metrics as $m | [$m[$d + ".longitudinal_max_m"], $m[$d + ".runup_time_s"],
      $m[$d + ".longitudinal_rest_m"], $m[$d + ".lateral_rest_m"], $m[$d + ".final_speed_m_s"],
      $m[$d + ".accel_peak_force_n"], $m[$d + ".accel_peak_force_30hz_n"]] | @tsv' "$out/run.json" |
    awk -F'\t' -v d="$d" '{ printf "| %s | %.3f | %.2f | %.3f | %.4f | %.3f | %.1f / %.1f |\n", d, $1, $2, $3, $4, $5, $6, $7 }'
done
