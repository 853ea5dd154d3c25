#!/usr/bin/env bash
# Runs (or resumes) a trade-off study of scenes/studies/ and prints its tables as docs/tradeoff.md shows them,
# headed by the commit and the machine (docs/measured_on.sh); copies the study's plot to docs/<name>.svg when FIG
# names it. The tables are `flume study tradeoff`'s own (DIR/tradeoff.md, without its title and plot line).
#   docs/tradeoff/study.sh SPEC [FLUME] [OUT]
# SPEC: e.g. scenes/studies/tradeoff_waseda_2d.json. THREADS (environment): OpenMP threads per run, replacing the
# spec's run.threads (its runs then read a copy of the spec in OUT, the scene paths made absolute).
# Cost on the 2-core VM, one thread per run: tradeoff_waseda_2d about 15 min, tradeoff_waseda_2d_vs_3d about
# 20 min (its 3D half basin), tradeoff_debris about 45 min, waseda_half_vs_full about 10 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
spec=$(realpath "$1")
flume=$(realpath "${2:-$root/build/bin/flume}")
name=$(basename "$spec" .json)
out=$(realpath -m "${3:-$name}")
mkdir -p "$out"
if [[ -n ${THREADS:-} ]]; then
  dir=$(dirname "$spec")
  jq --arg dir "$dir" --argjson t "$THREADS" '
      def abs: if startswith("/") then . else $dir + "/" + . end;
      .scene |= abs | .settings |= map(if has("scene") then .scene |= abs else . end) | .run.threads = $t
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
