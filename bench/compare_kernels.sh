#!/usr/bin/env bash
# The portable build's two copies of the CPU backends (solver/cpu_kernels.h) on one binary: FLUME_CPU_KERNELS=portable
# against the AVX2 copy, alternated run by run so that both see the same machine, on MPM in 3D (the dam break of
# about one million particles) and 2D (waseda_2d at dx 0.01 m) and SPH in 3D (the dam break of 170,000 particles),
# float, 1 and 2 threads, ROUNDS rounds (STEPS measured steps, 40 times as many in 2D). Prints one JSON line per run and a Markdown table of the medians:
# particle-steps per wall second and per CPU second (the latter compares on a machine shared with other jobs).
#
#   bench/compare_kernels.sh [FLUME] [ROUNDS] [STEPS]     defaults: build/bin/flume, 3 rounds, 10 measured steps
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flume=${1:-$root/build/bin/flume}
rounds=${2:-3}
steps=${3:-10}
[[ -x $flume ]] || { echo "compare_kernels.sh: no flume executable at $flume" >&2; exit 2; }
FLUME_CPU_KERNELS=avx2 "$flume" --version | grep -q "avx2 CPU kernels" ||
  { echo "compare_kernels.sh: $flume has no AVX2 copy, or this CPU no AVX2" >&2; exit 2; }
out=$(mktemp -d)
echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; $("$flume" --version)"
cases=(  # name|scene|options|measured steps in units of STEPS (a 2D step is a few ms)
  "mpm 3D|$root/bench/scenes/dam_break_3d_1m.json||1"
  "mpm 2D|$root/scenes/waseda/waseda_2d.json|--set solver.dx=0.01|40"
  "sph 3D|$root/bench/scenes/dam_break_3d_sph_170k.json||1"
)
for r in $(seq "$rounds"); do
  for c in "${cases[@]}"; do
    IFS='|' read -r name scene extra times <<<"$c"
    for t in 1 2; do
      for kernels in portable avx2; do
        load=$(cut -d' ' -f1 /proc/loadavg)
        # shellcheck disable=SC2086  # extra holds whole options
        FLUME_CPU_KERNELS=$kernels OMP_WAIT_POLICY=PASSIVE "$flume" bench "$scene" --steps $((steps * times)) --threads "$t" \
          --set solver.precision=float $extra |
          jq -c --arg name "$name" --arg k "$kernels" --arg load "$load" --argjson r "$r" \
            '{case: $name, kernels: $k, round: $r, threads, load_before: ($load | tonumber), particles,
              particle_steps_per_s, per_cpu_s: (.particle_steps_per_s * .wall_s / .cpu_s), cpu_kernels}' |
          tee -a "$out/runs.jsonl"
      done
    done
  done
done
echo
echo "| case | threads | portable: particle-steps/s (per CPU-s) | avx2: particle-steps/s (per CPU-s) | avx2/portable, wall (CPU) |"
echo "|---|---|---|---|---|"
jq -rs '
  def median: sort | if length % 2 == 1 then .[length / 2 | floor] else (.[length / 2 - 1] + .[length / 2]) / 2 end;
  def e(x): x / 1e6 * 1000 | round / 1000 | tostring + "e6";
  group_by([.case, .threads])[] as $g
  | ($g | map(select(.kernels == "portable"))) as $p | ($g | map(select(.kernels == "avx2"))) as $a
  | [($p | map(.particle_steps_per_s) | median), ($p | map(.per_cpu_s) | median),
     ($a | map(.particle_steps_per_s) | median), ($a | map(.per_cpu_s) | median)] as $m
  | "| \($g[0].case) | \($g[0].threads) | \(e($m[0])) (\(e($m[1]))) | \(e($m[2])) (\(e($m[3]))) | \($m[2] / $m[0] * 100 | round / 100) (\($m[3] / $m[1] * 100 | round / 100)) |"' \
  "$out/runs.jsonl"
