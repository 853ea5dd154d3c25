#!/usr/bin/env bash
# Issue 3 item 4 in 3D (docs/waseda.md, "Half basin against the full basin"): waseda_3d_half against waseda_3d,
# then waseda_apron fed bin by bin from the full run's apron_inflow section against the full run's WG3 and WG4.
# Both as `flume study tradeoff` campaigns (resumable). dx 0.05 m, 4 s: about 25 min on 2 cores.
#   docs/waseda_3d_compare.sh [FLUME] [OUT]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-waseda-3d-compare}")
mkdir -p "$out"
export OMP_WAIT_POLICY=PASSIVE
"$flume" study tradeoff "$root/scenes/studies/waseda_half_vs_full.json" --db "$out/half_vs_full.sqlite" --out "$out/half_vs_full"
full=$(sqlite3 "$out/half_vs_full.sqlite" "SELECT run_dir FROM runs WHERE scene LIKE '%waseda_3d.json' AND status = 'ok' LIMIT 1")
[[ -f $full/result.h5 ]] || { echo "no finished full-basin run in $out/half_vs_full.sqlite" >&2; exit 1; }
"$flume" calibrate target "$full/result.h5" --out "$out/full_wg34.csv" --gauge WG3 --gauge WG4
cat > "$out/apron_vs_full.json" <<JSON
{
  "name": "waseda-apron-vs-full",
  "description": "Issue 3 item 4: waseda_apron (x >= 4.35 m) fed bin by bin from the full basin's apron_inflow record, against the full basin's WG3 and WG4; dx 0.05 m, 5x2 columns, 4 s",
  "scene": "$root/scenes/waseda/waseda_apron.json",
  "overrides": {"solver.end_time": 4.0, "solver.dx": 0.05, "inflow.record": "$full/result.h5"},
  "settings": [{"label": "3D apron dx 0.05"}],
  "reference": {"records": "$out/full_wg34.csv"},
  "outputs": {"gauges": ["WG3", "WG4"], "window_s": [0, 4.0], "arrival_threshold_m": 0.005},
  "run": {"time_limit_s": 3600, "threads": 2}
}
JSON
(cd "$out" && "$flume" study tradeoff "$out/apron_vs_full.json" --db "$out/apron_vs_full.sqlite" --out "$out/apron_vs_full")
