#!/usr/bin/env bash
# Two flume binaries on the 3D dam break of about one million particles, alternated run by run so that both see
# the same machine (a shared VM's speed drifts by 15 % over minutes): float and double, 1 and 2 threads, ROUNDS
# rounds. Prints one JSON line per run and a Markdown table of the median particle-steps/s and ms per stage.
#
#   bench/compare_bench.sh BEFORE AFTER [ROUNDS] [STEPS]     defaults: 3 rounds of 20 measured steps
#
# Build each binary native (-DFLUME_NATIVE=ON, -DFLUME_TESTS=OFF) from its commit, e.g. with `git worktree`.
set -euo pipefail
[[ $# -ge 2 ]] || { sed -n 2,8p "$0" >&2; exit 2; }
before=$1 after=$2 rounds=${3:-3} steps=${4:-20}
for b in "$before" "$after"; do [[ -x $b ]] || { echo "compare_bench.sh: no flume executable at $b" >&2; exit 2; }; done
root=$(cd "$(dirname "$0")/.." && pwd)
scene=$root/bench/scenes/dam_break_3d_1m.json
out=$(mktemp -d)
echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores"
echo "# before: $("$before" --version)"
echo "# after:  $("$after" --version)"
for r in $(seq "$rounds"); do
  for p in float double; do
    for t in 1 2; do
      for which in before after; do
        bin=$before
        [[ $which == after ]] && bin=$after
        load=$(cut -d' ' -f1 /proc/loadavg)
        "$bin" bench "$scene" --steps "$steps" --threads "$t" --set solver.precision="$p" |
          jq -c --arg w "$which" --arg load "$load" --argjson r "$r" \
            '{which: $w, round: $r, precision, threads, load_before: ($load | tonumber),
              particle_steps_per_s, stage_ms: (.stage_s | map_values(. / '"$steps"' * 1000))}' |
          tee -a "$out/runs.jsonl"
      done
    done
  done
done
echo
echo "| precision | threads | before: particle-steps/s | after: particle-steps/s | after/before | before: P2G / grid / G2P ms | after: P2G / grid / G2P ms |"
echo "|---|---|---|---|---|---|---|"
jq -rs '
  def median: sort | if length % 2 == 1 then .[length / 2 | floor] else (.[length / 2 - 1] + .[length / 2]) / 2 end;
  def r1: . * 10 | round / 10;
  def e6: . / 1e6 * 100 | round / 100 | tostring + "e6";
  group_by([.precision, .threads])[] as $g
  | ($g | map(select(.which == "before"))) as $b | ($g | map(select(.which == "after"))) as $a
  | ($b | map(.particle_steps_per_s) | median) as $pb | ($a | map(.particle_steps_per_s) | median) as $pa
  | def stages(s): [(s | map(.stage_ms.p2g) | median | r1), (s | map(.stage_ms.grid) | median | r1),
                    (s | map(.stage_ms.g2p) | median | r1)] | map(tostring) | join(" / ");
    "| \($g[0].precision) | \($g[0].threads) | \($pb | e6) | \($pa | e6) | \($pa / $pb * 100 | round / 100) | \(stages($b)) | \(stages($a)) |"' \
  "$out/runs.jsonl"
