#!/usr/bin/env bash
# Issue 3 item 4 in 3D (docs/waseda.md, "Half basin against the full basin"), two parts, each resumable:
#  1. waseda_3d_half against waseda_3d at dx 0.04 m, 4 s (scenes/studies/waseda_half_vs_full_dx004.json;
#     about 14 min on 2 cores);
#  2. waseda_apron (half span, x >= 4.35 m) fed bin by bin from the apron_inflow section of a waseda_3d_half run
#     at dx 0.03 m, against that run's WG3 and WG4. The gate is opened to GATE (default 0.14 m, the top of the
#     paper's range) and the run lasts END_TIME (default 4.5 s): with the default 0.10 m gate only a film (under a
#     cell) reaches WG3 at this dx and none reaches WG4 within 5 s, in 2D or 3D. About 40 min on 2 cores. Draws
#     both runs' WG3 and WG4 into docs/waseda_apron_3d.svg (FIG=0: into OUT instead).
#   docs/waseda_3d_compare.sh [FLUME] [OUT] [PART: 1|2|all]
# THREADS (environment): OpenMP threads per run (default: the spec's 2 in part 1, 2 in part 2). Each part prints
# its results headed by the commit and the machine (docs/measured_on.sh); part 1 by docs/tradeoff/study.sh, into
# OUT/half_vs_full. One thread on the 2-core VM beside another developer's jobs (2026-12-05): part 1 28 min,
# part 2 36 min.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/docs/measured_on.sh"
flume=$(realpath "${1:-$root/build/bin/flume}")
out=$(realpath -m "${2:-waseda-3d-compare}")
part=${3:-all}
threads=${THREADS:-2}
gate=${GATE:-0.14}
end_time=${END_TIME:-4.5}
mkdir -p "$out"
export OMP_WAIT_POLICY=PASSIVE
if [[ $part == 1 || $part == all ]]; then
  "$root/docs/tradeoff/study.sh" "$root/scenes/studies/waseda_half_vs_full_dx004.json" "$flume" "$out/half_vs_full"
fi
if [[ $part == 2 || $part == all ]]; then
  [[ -f $out/apron_header.txt ]] || measured_on "$flume" "$threads" >"$out/apron_header.txt"  # the first start's
  cat "$out/apron_header.txt"
  echo
  feed=$out/half_dx003_g${gate}_t${end_time}
  if [[ ! -f $feed/run.json ]] || ! grep -q '"status": "ok"' "$feed/run.json"; then
    "$flume" run "$root/scenes/waseda/waseda_3d_half.json" --out "$feed" --threads "$threads" \
      --set solver.dx=0.03 --set solver.end_time="$end_time" --set reservoir.gate_height_m="$gate"
  fi
  "$flume" calibrate target "$feed/result.h5" --out "$out/half_wg34.csv" --gauge WG3 --gauge WG4
  apron=$out/apron_dx003_g${gate}_t${end_time}
  if [[ ! -f $apron/run.json ]] || ! grep -q '"status": "ok"' "$apron/run.json"; then
    "$flume" run "$root/scenes/waseda/waseda_apron.json" --out "$apron" --threads "$threads" --set basin.span=half \
      --set solver.dx=0.03 --set solver.end_time="$end_time" --set "inflow.record=$feed/result.h5"
  fi
  "$flume" calibrate target "$apron/result.h5" --out "$out/apron_wg34.csv" --gauge WG3 --gauge WG4
  # WG3 and WG4 of the apron run against the run that fed it: RMS of the difference over the run at the feeding
  # run's samples (100 Hz; the apron run's record interpolated linearly onto them) as a share of the feeding
  # run's peak, and the costs.
  python3 - "$out/half_wg34.csv" "$out/apron_wg34.csv" "$feed/run.json" "$apron/run.json" <<'PY'
import csv, json, math, sys
def read(path):
    rows = [r for r in csv.reader(l for l in open(path) if not l.startswith("#"))]
    head, data = rows[0], [[float(x) for x in r] for r in rows[1:]]
    return head, data
hf, feed = read(sys.argv[1])
ha, apron = read(sys.argv[2])
def at(rows, col, t):  # linear interpolation of column col at time t (rows sorted by time)
    lo, hi = 0, len(rows) - 1
    if t <= rows[0][0]: return rows[0][col]
    if t >= rows[-1][0]: return rows[-1][col]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if rows[mid][0] <= t: lo = mid
        else: hi = mid
    w = (t - rows[lo][0]) / (rows[hi][0] - rows[lo][0])
    return rows[lo][col] + w * (rows[hi][col] - rows[lo][col])
times = [r[0] for r in feed if r[0] <= apron[-1][0] + 1e-9]
n = len(times)
for c in range(1, len(hf)):
    ref = [feed[i][c] for i in range(n)]
    got = [at(apron, ha.index(hf[c]), t) for t in times]
    rms = math.sqrt(sum((a - b) ** 2 for a, b in zip(got, ref)) / n)
    peak = max(ref)
    print(f"{hf[c]}: RMS {rms * 1e3:.2f} mm = {100 * rms / peak:.1f} % of the feeding run's peak {peak:.4f} m; "
          f"apron run's peak {max(got):.4f} m")
costs = [json.load(open(p))["cost"] for p in sys.argv[3:5]]
for c in costs:
    c["particle_steps"] = c["particles"] * c["steps"]
for k in ("wall_s", "particle_steps", "particles", "steps", "peak_rss_mb"):
    print(f"{k}: feed {costs[0][k]:.4g}, apron {costs[1][k]:.4g}, ratio {costs[1][k] / costs[0][k]:.3f}")
PY
  # The two runs' WG3 and WG4 in one figure, docs/waseda_apron_3d.svg (FIG=0: into OUT instead).
  fig=$root/docs/waseda_apron_3d.svg
  [[ ${FIG:-1} == 1 ]] || fig=$out/waseda_apron_3d.svg
  "$flume" gauges "$feed=waseda_3d_half (feed)" "$apron=waseda_apron half span" --gauges WG3,WG4 \
    --title "waseda_apron fed from waseda_3d_half, dx 0.03 m, gate $gate m" --out "$fig" >"$out/apron_gauges.txt"
fi
