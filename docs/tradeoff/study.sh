#!/usr/bin/env bash
# Runs (or resumes) a trade-off study of scenes/studies/ and prints its tables as docs/tradeoff.md shows them,
# headed by the commit and the machine (docs/measured_on.sh); copies the study's plot to docs/<name>.svg when FIG
# names it. The tables are `flume study tradeoff`'s own (DIR/tradeoff.md, without its title and plot line).
#   docs/tradeoff/study.sh SPEC [FLUME] [OUT]
# SPEC: e.g. scenes/studies/tradeoff_waseda_2d.json. THREADS (environment): OpenMP threads per run, replacing the
# spec's run.threads (its runs then read a copy of the spec in OUT, the scene paths made absolute). REFERENCE
# (environment): the label of the setting to measure errors against, replacing the spec's reference (the same
# copy; the runs are the same, only the tables change: for a spec whose reference did not complete).
# Cost on the 2-core VM, one thread per run: tradeoff_waseda_2d about 15 min, tradeoff_waseda_2d_vs_3d about
# 20 min (its 3D half basin), tradeoff_debris about 15 min (2026-12-05: its dx 0.0075 m reference stops at 1.4 s),
# waseda_half_vs_full about 10 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
spec=$(realpath "$1")
flume=$(realpath "${2:-$root/build/bin/flume}")
name=$(basename "$spec" .json)
out=$(realpath -m "${3:-$name}")
mkdir -p "$out"
if [[ -n ${THREADS:-} || -n ${REFERENCE:-} ]]; then
  dir=$(dirname "$spec")
  jq --arg dir "$dir" --arg t "${THREADS:-}" --arg ref "${REFERENCE:-}" '
      def abs: if startswith("/") then . else $dir + "/" + . end;
      .scene |= abs | .settings |= map(if has("scene") then .scene |= abs else . end)
      | if $t != "" then .run.threads = ($t | tonumber) else . end
      | if $ref != "" then .reference = {"setting": $ref} else . end
      | if (.reference.records? // null) != null then .reference.records |= abs else . end' "$spec" >"$out/spec.json"
  spec=$out/spec.json
fi
threads=$(jq -r '.run.threads // 1' "$spec")
[[ -f $out/header.txt ]] || measured_on "$flume" "$threads" >"$out/header.txt"  # the first start's
header=$(cat "$out/header.txt")
OMP_WAIT_POLICY=PASSIVE "$flume" study tradeoff "$spec" --db "$out/study.sqlite" --out "$out/tables" >"$out/study.log"
echo "$header"
echo
sed -e '1{/^# /d}' -e '/^!\[error against wall time\]/d' "$out/tables/tradeoff.md"
if [[ -n ${FIG:-} ]]; then cp "$out/tables/tradeoff.svg" "$FIG"; fi
