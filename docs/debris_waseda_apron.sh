#!/usr/bin/env bash
# Issue 4 point 5: the Waseda apron fed by a 2D run, six upstream containers in two layers, and their top-down
# paths with the Naito (2014) cone and the Nistor (2017) eq. 58/59 guidelines (docs/debris.md, "The Waseda apron").
#   feed    scenes/waseda/waseda_2d.json at FEED_DX (0.01 m), FEED_END (END_TIME) s, gate GATE, reservoir filled to FILL
#           (0.90 m, the study's nominal value; its STAR-CCM+ twin used 0.67 m): the section record at x = 4.35 m
#           (at dx 0.02 m the 2D basin passes half the water over the quay that it does at 0.01 m: docs/debris.md)
#   5x2     scenes/waseda/waseda_apron.json, 5x2 columns, dx = DX (0.02 m), END_TIME (12 s) simulated
#   0x0     the same without obstacles at DX0 (0.03 m: the eq. 58 comparison)
#   paths   flume debris-paths over both runs -> $OUT/debris_paths.svg and the metric tables
# docs/debris/apron_tables.sh OUT then prints the tables docs/debris.md quotes, headed by OUT/header.txt (the commit
# and machine of the first start) with each run's cost (OUT/NAME.time).
# Usage: docs/debris_waseda_apron.sh [feed 5x2 0x0 paths]   (default: all four)
# Environment: FLUME (build/bin/flume), OUT (debris-apron), THREADS (2), DX, DX0, END_TIME, GATE (0.10 m), FILL, FEED_DX,
# BED_ROUGHNESS (0 m: the apron's k_s, basin.bed_roughness_m; the feed keeps its own scene's),
# FEED_END (END_TIME; the apron cannot run past the feed's record, whose last reading it would hold; a finished
# feed is kept whatever its length: remove OUT/feed2d to change it).
# The apron runs checkpoint every 10 min (docs/checkpoints.md): run the script again after a kill and each goes
# on from its checkpoint. Cost on the 2-core VM, 12 s: feed about 13 min at 0.01 m (1 thread); 0x0 at 0.03 m about 50 min
# (1 thread); 5x2 at 0.02 m about 2 h on 2 threads (session 11, commit e0dee22: 7,154 s, partly beside other jobs).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
FLUME=${FLUME:-$ROOT/build/bin/flume}
OUT=${OUT:-$ROOT/debris-apron}
THREADS=${THREADS:-2}
DX=${DX:-0.02}
DX0=${DX0:-0.03}
END_TIME=${END_TIME:-12}
GATE=${GATE:-0.10}
FILL=${FILL:-0.90}
FEED_DX=${FEED_DX:-0.01}
FEED_END=${FEED_END:-$END_TIME}
BED_ROUGHNESS=${BED_ROUGHNESS:-0}
STEPS=("$@")
[ ${#STEPS[@]} -eq 0 ] && STEPS=(feed 5x2 0x0 paths)
mkdir -p "$OUT"
cd "$OUT"
source "$ROOT/docs/measured_on.sh"
[[ -f header.txt ]] || measured_on "$FLUME" "$THREADS" >header.txt  # the first start's; docs/debris/apron_tables.sh prints it
timed() {  # timed NAME COMMAND...: appends the command's cost to NAME.time (a resumed run adds a line)
  local name=$1
  shift
  OMP_WAIT_POLICY=PASSIVE /usr/bin/time -a -o "$name.time" -f '%e s wall, %U s user, %S s system' "$@"
}
want() { for s in "${STEPS[@]}"; do [ "$s" = "$1" ] && return 0; done; return 1; }
debris=(--set debris.count=6 --set debris.layers=2 --set debris.placement=upstream)
if want feed && ! grep -qs '"status": "ok"' feed2d/run.json; then  # a finished feed is kept
  timed feed2d "$FLUME" run "$ROOT/scenes/waseda/waseda_2d.json" --out feed2d --set solver.dx="$FEED_DX" --set solver.end_time="$FEED_END" \
    --set reservoir.gate_height_m="$GATE" --set reservoir.fill_level_m="$FILL" --threads "$THREADS"
fi
apron() {  # apron NAME LAYOUT DX
  local resume=()
  [ -f "$1/checkpoint.bin" ] && resume=(--resume)
  timed "$1" "$FLUME" run "$ROOT/scenes/waseda/waseda_apron.json" --out "$1" --set solver.dx="$3" --set solver.end_time="$END_TIME" \
    --set inflow.record="$PWD/feed2d/result.h5" "${debris[@]}" --set obstacles.layout="$2" \
    --set basin.bed_roughness_m="$BED_ROUGHNESS" --threads "$THREADS" \
    --checkpoint-every 600 "${resume[@]}"
}
want 5x2 && apron apron_5x2 5x2 "$DX"
want 0x0 && apron apron_0x0 0x0 "$DX0"
if want paths; then
  "$FLUME" debris-paths apron_0x0 apron_5x2 --out debris_paths.svg | tee debris_paths.txt
fi
