#!/usr/bin/env bash
# docs/waseda.md, "Measured": waseda_2d for 6 s with the three forcing models at the scene's dx = 0.02 m and the
# exponential release at 0.04 m; prints the table (WG peak eta / peak time / arrival, from each run's run.json),
# a cost line per run, and draws docs/waseda_forcing_dx002.svg and docs/waseda_exponential_dx.svg with
# `flume gauges` (whose own peaks and arrivals go to OUT/gauges_*.txt).
#   docs/waseda/forcing_2d.sh [FLUME] [OUT]      THREADS (1), FIGS (1: write the figures into docs/)
# Cost on the 2-core VM, one thread: about 3 min (the three dx 0.02 m runs about 50 s each).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-waseda-forcing-2d}")
threads=${THREADS:-1}
mkdir -p "$out"
[[ -f $out/header.txt ]] || measured_on "$flume" "$threads" >"$out/header.txt"  # the first start's
header=$(cat "$out/header.txt")
scene=$root/scenes/waseda/waseda_2d.json
table='[[0,1],[0.3,0.6],[0.6,0.3],[1.0,0.1],[1.5,0]]'
run() {  # run NAME DX MODEL
  local extra=()
  [[ $3 == table ]] && extra=(--set "reservoir.forcing.table=$table")
  if ! grep -qs '"status": "ok"' "$out/$1/run.json"; then
    OMP_WAIT_POLICY=PASSIVE /usr/bin/time -o "$out/$1.time" -f '%e s wall, %U s user, %S s system' "$flume" run "$scene" --out "$out/$1" --quiet --threads "$threads" --set solver.dx="$2" \
      --set solver.end_time=6 --set reservoir.forcing.model="$3" "${extra[@]}"
  fi
}
run none_002 0.02 none
run exp_002 0.02 exponential
run table_002 0.02 table
run exp_004 0.04 exponential
echo "$header"
echo
echo "| forcing, dx | WG1 | WG2 | WG3 | WG4 |"
echo "|---|---|---|---|---|"
for r in "none_002 none, 0.02" "exp_002 exponential t99 = 0.8 s, 0.02" "table_002 table, 0.02" \
         "exp_004 exponential t99 = 0.8 s, 0.04"; do
  name=${r%% *} label=${r#* }
  jq -r '.metrics as $m | ["WG1", "WG2", "WG3", "WG4"] | map(
      if $m[. + ".arrival_s"] == null then "dry" else "\($m[. + ".peak_m"]) \($m[. + ".peak_time_s"]) \($m[. + ".arrival_s"])" end)
      | join("\t")' "$out/$name/run.json" | awk -F'\t' -v label="$label" '{
    printf "| %s |", label
    for (i = 1; i <= NF; i++) {
      if ($i == "dry") { printf " dry |"; continue }
      split($i, v, " "); printf " %.3f / %.2f / %.2f |", v[1], v[2], v[3]
    }
    printf "\n" }'
done
echo
for name in none_002 exp_002 table_002 exp_004; do
  echo "$name: $(jq -c '.cost' "$out/$name/run.json"); $(cat "$out/$name.time" 2>/dev/null)"
done
figdir=$out
[[ ${FIGS:-1} == 1 ]] && figdir=$root/docs
"$flume" gauges "$out/none_002=none" "$out/exp_002=exponential t99 0.8 s" "$out/table_002=table" \
  --out "$figdir/waseda_forcing_dx002.svg" --title "waseda_2d, dx 0.02 m: forcing models" >"$out/gauges_forcing.txt"
"$flume" gauges "$out/exp_002=dx 0.02" "$out/exp_004=dx 0.04" \
  --out "$figdir/waseda_exponential_dx.svg" --title "waseda_2d, exponential t99 0.8 s: dx 0.02 against 0.04 m" \
  >"$out/gauges_dx.txt"
