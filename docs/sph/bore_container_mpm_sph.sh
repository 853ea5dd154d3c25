#!/usr/bin/env bash
# docs/sph.md, "A debris case with both methods": scenes/debris/bore_container.json (a dam-break bore carrying a
# two-high container stack, 3D, 2 s) run by MPM and by SPH at each DX given, their debris metrics, the gauge's
# peak and the cost, headed by the commit and the machine.
#   docs/sph/bore_container_mpm_sph.sh [FLUME] [OUT] [DX...]     THREADS (1)
# Cost on the 2-core VM, one thread: dx 0.03 m about 1 min (MPM) and 8 min (SPH).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-bore-container-mpm-sph}")
shift $(( $# < 2 ? $# : 2 ))
dxs=("${@:-0.03}")
threads=${THREADS:-1}
rows=()
mkdir -p "$out"
for dx in "${dxs[@]}"; do
  for method in mpm sph; do
    dir=$out/${method}_dx$dx
    run_scene_once "$flume" "$root/scenes/debris/bore_container.json" "$dir" "$threads" \
      --set solver.method=$method --set solver.dx=$dx >"$dir.log"
    head -1 "$dir.log"
    for d in D1 D2; do
      rows+=("$(jq -r --arg d "$d" --arg m "$method" --arg dx "$dx" '.metrics as $x | [$m, $dx, $d,
          $x[$d + ".longitudinal_max_m"], $x[$d + ".runup_time_s"], $x[$d + ".longitudinal_rest_m"],
          $x[$d + ".lateral_rest_m"], $x[$d + ".final_speed_m_s"], $x["G1.peak_m"], .cost.particles,
          .cost.wall_s] | @tsv' "$dir/run.json")")
    done
  done
done
echo
echo "| method | dx (m) | debris | run-up (m) | at (s) | longitudinal at 2 s (m) | lateral at 2 s (m) | speed at 2 s (m/s) | G1 peak (m) | particles | wall (s) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for r in "${rows[@]}"; do
  awk -F'\t' '{ printf "| %s | %s | %s | %.3f | %.2f | %.3f | %.4f | %.3f | %.3f | %d | %.0f |\n",
    $1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11 }' <<<"$r"
done
