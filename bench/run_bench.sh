#!/usr/bin/env bash
# Solver speed on the 3D dam break of about one million particles (issue 2, item 8), and the sparse-grid
# check (the same water in a domain of 20 times the volume). Prints one JSON object per run (flume bench's
# output plus the load average before it) and a Markdown table for docs/benchmarks.md.
#
#   bench/run_bench.sh [FLUME] [STEPS]      defaults: a native build, 40 measured steps
#
# Without FLUME it builds flume native (-DFLUME_NATIVE=ON: -march=native) in build-native/ and says so; the
# default build is portable (docs/benchmarks.md compares the two).
#
# Other work on the machine skews the figures: the script records `uptime`'s 1-minute load before each run;
# measure when it is below about 0.5.
set -euo pipefail
echo "# load before: $(cat /proc/loadavg)"
root=$(cd "$(dirname "$0")/.." && pwd)
flume=${1:-}
if [[ -z $flume ]]; then
  echo "# building flume with -DFLUME_NATIVE=ON (-march=native) in $root/build-native"
  cmake -S "$root" -B "$root/build-native" -DCMAKE_BUILD_TYPE=Release -DFLUME_NATIVE=ON -DFLUME_TESTS=OFF >/dev/null
  cmake --build "$root/build-native" -j2 --target flume >/dev/null
  flume=$root/build-native/bin/flume
fi
steps=${2:-40}
scene=$root/bench/scenes/dam_break_3d_1m.json
out=${BENCH_OUT:-$(mktemp -d)}
[[ -x $flume ]] || { echo "run_bench.sh: no flume executable at $flume (build first)" >&2; exit 2; }
# Which build this is: the figures of docs/benchmarks.md are native unless they say otherwise.
echo "# $("$flume" --version)"

echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, $(git -C "$root" describe --always --dirty)"
run() {  # run NAME THREADS PRECISION [--set ...]
  local name=$1 threads=$2 precision=$3
  shift 3
  local load
  load=$(cut -d' ' -f1 /proc/loadavg)
  # The process's CPU time (setup included) beside flume bench's wall time of the measured steps: with one
  # thread on a busy machine, process_cpu_s says how much of the wall time the run actually had a core.
  /usr/bin/time -f '%U %S' -o "$out/$name.time" \
    "$flume" bench "$scene" --steps "$steps" --threads "$threads" --set solver.precision="$precision" "$@" \
    >"$out/$name.json"
  jq -c --arg name "$name" --arg load "$load" --arg cpu "$(awk '{print $1 + $2}' "$out/$name.time")" \
    '{name: $name, load_before: ($load | tonumber), process_cpu_s: ($cpu | tonumber)} + . | del(.scene)' \
    "$out/$name.json" | tee "$out/$name.line"
}
for p in float double; do
  for t in 1 2; do run "${p}_t$t" "$t" "$p"; done
done
# Sparse grid: the domain box grown by 20^(1/3) = 2.714 on every axis (20 times the volume), same water.
run float_t2_big 2 float --set 'domain.hi=[8.908, 1.579, 2.8]'

echo
echo "| run | threads | precision | particles | steps | s/step | particle-steps/s | per CPU-s | grid MB | peak RSS MB | process CPU s | load before |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for f in "$out"/*.line; do
  jq -r '"| \(.name) | \(.threads) | \(.precision) | \(.particles) | \(.steps) | \(.wall_s / .steps * 1000 | round / 1000) | \(.particle_steps_per_s | . / 1e6 * 100 | round / 100)e6 | \(.particle_steps_per_cpu_s | . / 1e6 * 100 | round / 100)e6 | \(.grid_mb | round) | \(.peak_rss_mb | round) | \(.process_cpu_s) | \(.load_before) |"' "$f"
done
# Where the time goes (ms per step by stage, wall clock) and the memory traffic: bytes a particle-step moves as
# the solver counts them, and the rate they moved at against the two cores' ceiling (about 43 GB/s).
echo
echo "| run | sort ms | P2G ms | grid ms | G2P ms | instruments ms | bytes/particle-step | GB/s |"
echo "|---|---|---|---|---|---|---|---|"
for f in "$out"/*.line; do
  jq -r 'def ms(s): if .stage_s[s] == null then "-" else (.stage_s[s] / .steps * 1e4 | round / 10 | tostring) end;
    "| \(.name) | \(ms("sort")) | \(ms("p2g")) | \(ms("grid")) | \(ms("g2p")) | \(ms("instruments")) | \(.bytes_per_particle_step // 0 | round) | \(.memory_gb_per_s // 0 | . * 10 | round / 10) |"' "$f"
done
jq -rs 'map({(.name): .}) | add | "sparse grid (float, 2 threads): time per step x\((.float_t2_big.wall_s / .float_t2_big.steps) / (.float_t2.wall_s / .float_t2.steps) * 1000 | round / 1000), grid memory x\(.float_t2_big.grid_mb / .float_t2.grid_mb * 1000 | round / 1000)"' "$out"/float_t2.line "$out"/float_t2_big.line
