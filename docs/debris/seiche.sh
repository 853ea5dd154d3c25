#!/usr/bin/env bash
# docs/debris.md, "Where the water settles": the 2D feed at dx 0.01 m with the reservoir at 0.67 m (waseda_2d, 24 s,
# the feed docs/debris_waseda_apron.sh makes with FILL=0.67 FEED_END=24) and the range of WG3, WG4 and WG2 over each
# 2 s from 12 to 24 s (mm above still water), from `flume export --csv`; headed by the commit and the machine.
#   docs/debris/seiche.sh [FLUME] [OUT]     THREADS (1)
# Cost on the 2-core VM, one thread: about 20 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/docs/measured_on.sh"
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-seiche}")
threads=${THREADS:-1}
mkdir -p "$out"
[[ -f $out/header.txt ]] || measured_on "$flume" "$threads" >"$out/header.txt"  # the first start's
run=$out/feed2d
if ! grep -qs '"status": "ok"' "$run/run.json"; then
  OMP_WAIT_POLICY=PASSIVE /usr/bin/time -o "$out/feed2d.time" -f '%e s wall, %U s user, %S s system' \
    "$flume" run "$root/scenes/waseda/waseda_2d.json" --out "$run" --quiet --threads "$threads" --set solver.dx=0.01 \
    --set solver.end_time=24 --set reservoir.gate_height_m=0.10 --set reservoir.fill_level_m=0.67
fi
rm -rf "$out/csv" && "$flume" export "$run" --csv "$out/csv" >/dev/null
cat "$out/header.txt"
echo
echo "cost: $(jq -c .cost "$run/run.json"); $(cat "$out/feed2d.time" 2>/dev/null)"
jq -r '.metrics | "WG1 peak \(.["WG1.peak_m"]) m at \(.["WG1.peak_time_s"]) s, WG3 \(.["WG3.peak_m"]) m, WG4 \(.["WG4.peak_m"]) m"' "$run/run.json"
echo
echo "| gauge | 12-14 s | 14-16 s | 16-18 s | 18-20 s | 20-22 s | 22-24 s |"
echo "|---|---|---|---|---|---|---|"
for g in "WG3 (x = 4.69 m)" "WG4 (x = 6.15 m)" "WG2 (basin)"; do
  awk -F, -v g="${g%% *}" -v label="$g" 'NR > 1 && $1 == g && $2 >= 12 && $2 <= 24 {
      k = int(($2 - 12) / 2); if (k > 5) k = 5; e = 1000 * $3
      if (!(k in lo) || e < lo[k]) lo[k] = e; if (!(k in hi) || e > hi[k]) hi[k] = e }
    END { printf "| %s |", label; for (k = 0; k < 6; k++) printf " %.1f-%.1f |", lo[k], hi[k]; printf "\n" }' \
    "$out/csv/gauges.csv"
done
