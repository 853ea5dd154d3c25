#!/usr/bin/env bash
# docs/debris.md, "The Waseda apron with six containers": the tables of the runs docs/debris_waseda_apron.sh made
# in OUT (feed2d/, apron_0x0/, apron_5x2/): per apron run its header (commit, machine), cost, the six
# containers' metrics, and the sheet over the apron at WG3 and WG4 (time deeper than a container's draft, peak
# depth), as docs/debris.md quotes them.
#   docs/debris/apron_tables.sh OUT [FLUME]
# Needs jq and `flume export`; reads only, runs nothing. Cost: seconds.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=$(realpath "${1:?usage: docs/debris/apron_tables.sh OUT [FLUME]}")
flume=$(realpath "${2:-$root/build/bin/flume}")
apron_m=0.025  # the apron's height above still water (0.255 - 0.23 m)
draft_m=$(awk 'BEGIN { printf "%.5f", 0.06 * 418.5 / 998 }')  # a Waseda container: 6 cm at 418.5 kg/m^3

[[ -f $out/header.txt ]] && cat "$out/header.txt"
if [[ -f $out/feed2d/run.json ]]; then
  echo
  echo "feed2d: status $(jq -r .status "$out/feed2d/run.json"); cost $(jq -c .cost "$out/feed2d/run.json")"
fi
for run in apron_0x0 apron_5x2; do
  dir=$out/$run
  [[ -f $dir/run.json ]] || continue
  echo
  echo "## $run: status $(jq -r .status "$dir/run.json"); cost $(jq -c .cost "$dir/run.json")"
  [[ -f $out/$run.time ]] && echo "time: $(cat "$out/$run.time")"
  jq -r '.metrics | "debris.mobilised_count \(.["debris.mobilised_count"]), debris.at_rest_count \(.["debris.at_rest_count"])"' "$dir/run.json"
  echo
  echo "| debris | longitudinal max (m) | at (s) | at the end (m) | lateral run-up / end (m) | spreading run-up / end (deg) | last faster than 1 cm/s (s) | speed at the end (m/s) | accelerometer 30 Hz (N) | at rest |"
  echo "|---|---|---|---|---|---|---|---|---|---|"
  for d in D1 D2 D3 D4 D5 D6; do
    jq -r --arg d "$d" '.metrics as $m | [$m[$d + ".longitudinal_max_m"], $m[$d + ".runup_time_s"],
        $m[$d + ".longitudinal_rest_m"], $m[$d + ".lateral_runup_m"], $m[$d + ".lateral_rest_m"],
        $m[$d + ".spreading_runup_deg"], $m[$d + ".spreading_rest_deg"], $m[$d + ".moving_until_s"],
        $m[$d + ".final_speed_m_s"], $m[$d + ".accel_peak_force_n"], $m[$d + ".at_rest"]] | map(. // "nan") | @tsv' \
      "$dir/run.json" |
      awk -F'\t' -v d="$d" '{ printf "| %s | %.3f | %.2f | %.3f | %.3f / %.3f | %.2f / %.2f | %.2f | %.3f | %.1f | %s |\n",
        d, $1, $2, $3, $4, $5, $6, $7, $8, $9, $10, ($11 == 1 ? "yes" : "no") }'
  done
  jq -r '[.metrics | to_entries[] | select(.key | test("^D[1-6]\\.longitudinal_max_m$")) | .value] |
    "mean longitudinal maximum \(add / length | . * 1000 | round / 1000) m"' "$dir/run.json"
  csv=$(mktemp -d)
  "$flume" export "$dir" --csv "$csv" >/dev/null
  echo
  echo "| gauge | time deeper than the draft ($draft_m m) over the apron (s) | peak depth over the apron (mm) | at (s) |"
  echo "|---|---|---|---|"
  for g in WG3 WG4; do
    awk -F, -v g="$g" -v apron="$apron_m" -v draft="$draft_m" '
      $1 == g { t = $2; h = $3 - apron
                if (n++ && prev_h > draft) wet += t - prev_t
                if (h > peak || n == 1) { peak = h; at = t }
                prev_t = t; prev_h = h }
      END { if (n) printf "| %s | %.2f | %.1f | %.2f |\n", g, wet, 1000 * peak, at }' "$csv/gauges.csv"
  done
  rm -rf "$csv"
done
