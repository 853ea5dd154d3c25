#!/usr/bin/env bash
# Issue 3 item 4 in 3D (docs/waseda.md, "Half basin against the full basin"), two parts, each resumable:
#  1. waseda_3d_half against waseda_3d at dx 0.04 m, 4 s (scenes/studies/waseda_half_vs_full_dx004.json;
#     about 14 min on 2 cores);
#  2. waseda_apron (half span, x >= 4.35 m) fed bin by bin from the apron_inflow section of a waseda_3d_half run
#     at dx 0.03 m, 5 s, against that run's WG3 and WG4 (at 0.04 m the bore does not reach WG4 within 6 s, in 2D
#     either; at 0.03 m it does by 3.3 s); about 25 min.
#   docs/waseda_3d_compare.sh [FLUME] [OUT] [PART: 1|2|all]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-waseda-3d-compare}")
part=${3:-all}
mkdir -p "$out"
export OMP_WAIT_POLICY=PASSIVE
if [[ $part == 1 || $part == all ]]; then
  "$flume" study tradeoff "$root/scenes/studies/waseda_half_vs_full_dx004.json" --db "$out/half_vs_full.sqlite" \
    --out "$out/half_vs_full"
fi
if [[ $part == 2 || $part == all ]]; then
  feed=$out/half_dx003
  if [[ ! -f $feed/run.json ]] || ! grep -q '"status": "ok"' "$feed/run.json"; then
    "$flume" run "$root/scenes/waseda/waseda_3d_half.json" --out "$feed" --threads 2 \
      --set solver.dx=0.03 --set solver.end_time=5
  fi
  "$flume" calibrate target "$feed/result.h5" --out "$out/half_wg34.csv" --gauge WG3 --gauge WG4
  cat > "$out/apron_vs_half.json" <<JSON
{
  "name": "waseda-apron-vs-half",
  "description": "Issue 3 item 4: waseda_apron (half span, x >= 4.35 m) fed bin by bin from a waseda_3d_half run's apron_inflow record, against that run's WG3 and WG4; dx 0.03 m, 5x2 columns, 5 s",
  "scene": "$root/scenes/waseda/waseda_apron.json",
  "overrides": {"basin.span": "half", "solver.end_time": 5.0, "solver.dx": 0.03, "inflow.record": "$feed/result.h5"},
  "settings": [{"label": "3D apron dx 0.03"}],
  "reference": {"records": "$out/half_wg34.csv"},
  "outputs": {"gauges": ["WG3", "WG4"], "window_s": [0, 5.0], "arrival_threshold_m": 0.005},
  "run": {"time_limit_s": 3600, "threads": 2}
}
JSON
  (cd "$out" && "$flume" study tradeoff "$out/apron_vs_half.json" --db "$out/apron_vs_half.sqlite" --out "$out/apron_vs_half")
  python3 - "$feed/run.json" "$out/apron_vs_half.sqlite" <<'PY'
import json, sqlite3, sys
feed = json.load(open(sys.argv[1]))["cost"]
db = sqlite3.connect(sys.argv[2])
run_dir = db.execute("SELECT run_dir FROM runs WHERE status = 'ok' LIMIT 1").fetchone()[0]
apron = json.load(open(run_dir + "/run.json"))["cost"]
for c in (feed, apron):
    c["particle_steps"] = c["particles"] * c["steps"]
for k in ("wall_s", "particle_steps", "particles", "steps", "peak_rss_mb"):
    print(f"{k}: feed {feed[k]:.4g}, apron {apron[k]:.4g}, ratio {apron[k] / feed[k]:.3f}")
PY
fi
