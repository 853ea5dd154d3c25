#!/usr/bin/env bash
# Issue 6, the twin experiments on the Waseda 2D scene (docs/calibration.md, "Waseda twin experiment"):
#   exp     WG1 simulated at t99 = 0.8 s, gate 0.085 m (dx = 0.02 m) plus 2 mm of noise is the target;
#           BOBYQA from t99 = 0.2 s, gate 0.12 m, at most 80 evaluations; profiles through the optimum
#   global  the same target, CRS2_LM (polished by BOBYQA) from three starts
#   fixed   each parameter alone, the other held at its true value (the fallback when WG1 cannot separate them)
#   table   the table forcing (5 control points, all holds free from 0.5) against its own twin target
#   resume  `exp` again under another name, killed with SIGKILL after RESUME_AFTER runs, then rerun: it must end
#           where `exp` ended, running no finished run again
# Usage: docs/calibration_twin.sh [all|exp|global|fixed|table|resume ...]   (default: all)
# Environment: FLUME (build/bin/flume), SCENE (scenes/waseda/waseda_2d.json), OUT (calibration-twin), DX (0.02),
#   END_TIME (6, s simulated), WINDOW ("0, 6"), WORKERS (2: runs at once), THREADS (1: per run),
#   TIME_LIMIT_S (3600 per run), NOISE_M (0.002: the target noise, m), RESUME_AFTER (10), XTOL (1e-4: xtol_abs of every optimizer),
#   STAGES ("": none; "1.5, 2.2": exp's window continuation, objective.stages), STANDIN (0; 1: the `gauge` test stand-in model instead of
#   the scene, to check this script in minutes: its numbers say nothing about the flume).
# Everything lands in $OUT: truth runs, target CSVs, one store (study.db), one folder per calibration with
# calibration.json, fit.svg, profiles.svg, history.svg; summary.txt collects the numbers for the docs.
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
FLUME=${FLUME:-$ROOT/build/bin/flume}
SCENE=${SCENE:-$ROOT/scenes/waseda/waseda_2d.json}
OUT=${OUT:-$ROOT/calibration-twin}
DX=${DX:-0.02}
END_TIME=${END_TIME:-6}
WINDOW=${WINDOW:-"0, 6"}
WORKERS=${WORKERS:-2}
THREADS=${THREADS:-1}
TIME_LIMIT_S=${TIME_LIMIT_S:-3600}
RESUME_AFTER=${RESUME_AFTER:-10}
XTOL=${XTOL:-1e-4}
STANDIN=${STANDIN:-0}
NOISE_M=${NOISE_M:-0.002}
STAGES=${STAGES:-}
TRUE_T99=0.8
TRUE_GATE=0.085
TRUE_TABLE='[[0, 1], [0.3, 0.75], [0.6, 0.4], [0.9, 0.15], [1.2, 0]]'
STEPS=("$@")
[ ${#STEPS[@]} -eq 0 ] && STEPS=(all)

[ -x "$FLUME" ] || { echo "no flume executable at $FLUME (set FLUME)" >&2; exit 2; }
[ "$STANDIN" = 1 ] || [ -f "$SCENE" ] || { echo "no scene at $SCENE (set SCENE)" >&2; exit 2; }
mkdir -p "$OUT"
DB="$OUT/study.db"
want() { for s in "${STEPS[@]}"; do [ "$s" = all ] || [ "$s" = "$1" ] && return 0; done; return 1; }
log() { echo "[$(date +%H:%M:%S)] $*" | tee -a "$OUT/summary.txt"; }

if [ "$STANDIN" = 1 ]; then
  SIMULATOR='"model": "gauge"'
  COMMON_OVERRIDES="\"solver.end_time\": $END_TIME"
  SIM_CMD=("$FLUME" model gauge --set solver.end_time=$END_TIME)
else
  SIMULATOR="\"scene\": \"$SCENE\""
  COMMON_OVERRIDES="\"solver.dx\": $DX, \"solver.end_time\": $END_TIME"
  SIM_CMD=("$FLUME" run "$SCENE" --threads "$THREADS" --set solver.dx=$DX --set solver.end_time=$END_TIME)
fi
timer=()
[ -x /usr/bin/time ] && timer=(/usr/bin/time -v)
RUN_SETTINGS="{\"time_limit_s\": $TIME_LIMIT_S, \"threads\": $THREADS}"

# truth NAME --set ... : one solver run at the true parameters, and its WG1 with 2 mm of noise as the target.
truth() {
  local name=$1
  shift
  if [ ! -f "$OUT/$name/result.h5" ]; then
    log "truth run $name: $*"
    "${timer[@]}" "${SIM_CMD[@]}" --out "$OUT/$name" "$@" 2> "$OUT/$name.time.log" > "$OUT/$name.log"
  fi
  "$FLUME" calibrate target "$OUT/$name/result.h5" --out "$OUT/$name.wg1.csv" --gauge WG1 --noise-m $NOISE_M \
    --seed 7 | tee -a "$OUT/summary.txt"
}

# calibrate NAME SPEC_TEXT: write the spec and run it (resumes when the store has it already).
calibrate() {
  local name=$1 spec=$2
  echo "$spec" > "$OUT/$name.json"
  log "calibrate $name"
  "$FLUME" calibrate "$OUT/$name.json" --db "$DB" --out "$OUT/$name" --workers "$WORKERS" | tee -a "$OUT/summary.txt"
}

two_params() {  # $1: t99 start, $2: gate start
  echo "[{\"path\": \"reservoir.forcing.t99_s\", \"lower\": 0.05, \"upper\": 2.0, \"start\": $1},
              {\"path\": \"reservoir.gate_height_m\", \"lower\": 0.04, \"upper\": 0.16, \"start\": $2}]"
}

exp_spec() {  # $1: name
  cat <<EOF
{"name": "$1", $SIMULATOR,
 "description": "issue 6 point 1: twin of WG1 at t99 = $TRUE_T99 s, gate $TRUE_GATE m, dx = $DX m, 2 mm noise",
 "overrides": {$COMMON_OVERRIDES, "reservoir.forcing.model": "exponential"},
 "targets": [{"file": "$OUT/truth_exp.wg1.csv", "gauge": "WG1"}],
 "parameters": $(two_params 0.2 0.12),
 "objective": {"window": [$WINDOW]${STAGES:+, \"stages\": [$STAGES]}},
 "algorithm": {"name": "BOBYQA", "max_evaluations": 80, "xtol_abs": $XTOL},
 "profile": {"points": 3, "span": 0.1},
 "run": $RUN_SETTINGS}
EOF
}

if want exp || want global || want fixed || want resume; then
  truth truth_exp --set reservoir.forcing.model=exponential --set reservoir.forcing.t99_s=$TRUE_T99 \
    --set reservoir.gate_height_m=$TRUE_GATE
fi

want exp && calibrate exp "$(exp_spec exp)"

if want global; then
  calibrate global "$(cat <<EOF
{"name": "global", $SIMULATOR,
 "overrides": {$COMMON_OVERRIDES, "reservoir.forcing.model": "exponential"},
 "targets": [{"file": "$OUT/truth_exp.wg1.csv", "gauge": "WG1"}],
 "parameters": $(two_params 0.2 0.12),
 "starts": [{"reservoir.forcing.t99_s": 1.8, "reservoir.gate_height_m": 0.05},
            {"reservoir.forcing.t99_s": 0.1, "reservoir.gate_height_m": 0.15}],
 "objective": {"window": [$WINDOW]},
 "algorithm": {"name": "CRS2_LM", "max_evaluations": 40, "polish": "BOBYQA", "polish_evaluations": 40,
               "xtol_abs": $XTOL, "seed": 3},
 "profile": {"points": 0},
 "run": $RUN_SETTINGS}
EOF
)"
fi

if want fixed; then
  calibrate fixed_t99 "$(cat <<EOF
{"name": "fixed_t99", $SIMULATOR,
 "overrides": {$COMMON_OVERRIDES, "reservoir.forcing.model": "exponential", "reservoir.gate_height_m": $TRUE_GATE},
 "targets": [{"file": "$OUT/truth_exp.wg1.csv", "gauge": "WG1"}],
 "parameters": [{"path": "reservoir.forcing.t99_s", "lower": 0.05, "upper": 2.0, "start": 0.2}],
 "objective": {"window": [$WINDOW]},
 "algorithm": {"name": "SBPLX", "max_evaluations": 40, "xtol_abs": $XTOL},
 "profile": {"points": 3, "span": 0.1},
 "run": $RUN_SETTINGS}
EOF
)"
  calibrate fixed_gate "$(cat <<EOF
{"name": "fixed_gate", $SIMULATOR,
 "overrides": {$COMMON_OVERRIDES, "reservoir.forcing.model": "exponential", "reservoir.forcing.t99_s": $TRUE_T99},
 "targets": [{"file": "$OUT/truth_exp.wg1.csv", "gauge": "WG1"}],
 "parameters": [{"path": "reservoir.gate_height_m", "lower": 0.04, "upper": 0.16, "start": 0.12}],
 "objective": {"window": [$WINDOW]},
 "algorithm": {"name": "SBPLX", "max_evaluations": 40, "xtol_abs": $XTOL},
 "profile": {"points": 3, "span": 0.1},
 "run": $RUN_SETTINGS}
EOF
)"
fi

if want table; then
  truth truth_table --set reservoir.forcing.model=table --set "reservoir.forcing.table=$TRUE_TABLE" \
    --set reservoir.gate_height_m=$TRUE_GATE
  params=""
  for i in 0 1 2 3 4; do
    params+="${params:+, }{\"path\": \"reservoir.forcing.table.$i.1\", \"lower\": 0, \"upper\": 1, \"start\": 0.5}"
  done
  calibrate table "$(cat <<EOF
{"name": "table", $SIMULATOR,
 "description": "issue 6 point 2: the 5 hold fractions of the table forcing, all free from 0.5",
 "overrides": {$COMMON_OVERRIDES, "reservoir.forcing.model": "table", "reservoir.gate_height_m": $TRUE_GATE,
               "reservoir.forcing.table": [[0, 0.5], [0.3, 0.5], [0.6, 0.5], [0.9, 0.5], [1.2, 0.5]]},
 "targets": [{"file": "$OUT/truth_table.wg1.csv", "gauge": "WG1"}],
 "parameters": [$params],
 "objective": {"window": [$WINDOW]},
 "algorithm": {"name": "BOBYQA", "max_evaluations": 80, "xtol_abs": $XTOL},
 "profile": {"points": 2, "span": 0.1},
 "run": $RUN_SETTINGS}
EOF
)"
fi

if want resume; then
  # `exp` under another name in another store, killed after RESUME_AFTER finished runs, then run again.
  spec_text=$(exp_spec resume)
  echo "$spec_text" > "$OUT/resume.json"
  rm -f "$OUT/resume.db"*
  log "calibrate resume: kill -9 after $RESUME_AFTER runs"
  "$FLUME" calibrate "$OUT/resume.json" --db "$OUT/resume.db" --out "$OUT/resume" --workers "$WORKERS" \
    > "$OUT/resume.killed.log" 2>&1 &
  pid=$!
  until [ -f "$OUT/resume.db" ] && [ "$(sqlite3 "$OUT/resume.db" "SELECT count(*) FROM runs WHERE status = 'ok'" 2>/dev/null || echo 0)" -ge "$RESUME_AFTER" ]; do
    sleep 5
    kill -0 $pid 2> /dev/null || break
  done
  kill -9 $pid 2> /dev/null || true
  wait $pid 2> /dev/null || true
  sqlite3 "$OUT/resume.db" "SELECT id, finished FROM runs WHERE status = 'ok' ORDER BY id" > "$OUT/resume.before.txt"
  "$FLUME" calibrate "$OUT/resume.json" --db "$OUT/resume.db" --out "$OUT/resume" --workers "$WORKERS" | tee -a "$OUT/summary.txt"
  sqlite3 "$OUT/resume.db" "SELECT id, finished FROM runs WHERE status = 'ok' ORDER BY id" | head -n "$(wc -l < "$OUT/resume.before.txt")" > "$OUT/resume.after.txt"
  if cmp -s "$OUT/resume.before.txt" "$OUT/resume.after.txt"; then log "resume: no finished run was run again"; else log "resume: FINISHED RUNS WERE REDONE"; fi
  log "resume: runs started twice: $(sqlite3 "$OUT/resume.db" "SELECT sum(attempts) - count(*) FROM runs")"
fi

# The numbers docs/calibration.md asks for.
python3 - "$OUT" "$TRUE_T99" "$TRUE_GATE" << 'EOF' | tee -a "$OUT/summary.txt"
import json, os, sys
out, t99, gate = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
truth = {"reservoir.forcing.t99_s": t99, "reservoir.gate_height_m": gate}
table = [[0, 1], [0.3, 0.75], [0.6, 0.4], [0.9, 0.15], [1.2, 0]]
def hold(tab, t):
    if t >= tab[-1][0]: return tab[-1][1]
    k = 1
    while tab[k][0] < t: k += 1
    return tab[k-1][1] + (t - tab[k-1][0]) / (tab[k][0] - tab[k-1][0]) * (tab[k][1] - tab[k-1][1])
for name in ["exp", "global", "fixed_t99", "fixed_gate", "table", "resume"]:
    f = os.path.join(out, name, "calibration.json")
    if not os.path.exists(f): continue
    j = json.load(open(f))
    b = j["best"]
    print(f"{name}: status {j['status']}, objective {b['terms']['objective']:.5g} m, RMS {b['terms']['rms_m']:.5g} m, "
          f"{j['evaluations']['optimizer']} optimizer + {j['evaluations']['profile']} profile evaluations, "
          f"{j['evaluations']['runs_in_store']} runs, {j['cost']['run_wall_s_mean']:.1f} s per run, "
          f"{j['cost']['run_wall_s_total'] / 3600:.2f} h of runs, {j['cost']['calibration_wall_s'] / 3600:.2f} h wall")
    for p, v in b["parameters"].items():
        ref = truth.get(p)
        err = f" ({100 * (v - ref) / ref:+.1f} % of the truth {ref})" if ref else ""
        print(f"    {p} = {v:.5g}{err}")
    for s in j["starts"]:
        print(f"    start {s['index']}: {s['objective']:.5g} m after {s['evaluations']}+{s['polish_evaluations']}, "
              f"same optimum: {s['same_optimum']}, {s['stop']}")
    ident = j["identifiability"]
    if ident.get("available"):
        print(f"    identifiability: correlation {ident['correlation']}, condition number {ident['condition_number']:.3g}, "
              f"std errors {ident['std_error']}")
    if name == "table":
        fit = [[t, b["parameters"][f"reservoir.forcing.table.{i}.1"]] for i, (t, _) in enumerate(table)]
        worst = max(abs(hold(fit, k / 1000) - hold(table, k / 1000)) for k in range(1501))
        print(f"    hold curve: max |f_fit - f_true| = {worst:.3f} (issue 6 asks <= 0.1)")
EOF
