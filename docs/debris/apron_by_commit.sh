#!/usr/bin/env bash
# docs/debris.md, "What carried the containers twice as far": the no-obstacle Waseda apron run by the solver of
# each COMMIT given, all fed by one 2D feed, so that only the apron's solver differs. For each commit: a git
# worktree and a CPU-only build of `flume` under WORK, the apron at DX0 (0.03 m) to END_TIME, then the
# containers' travel and speed and the depth over the apron at WG3 and WG4; last, the feed's own WG3 and WG4
# (the 2D basin at dx 0.01 m over the same apron: with no obstacle the 3D flow should be the 2D one, up to
# resolution).
#   FEED=DIR WORK=DIR docs/debris/apron_by_commit.sh COMMIT...
# FEED: a feed2d folder of docs/debris_waseda_apron.sh (e.g. OUT/feed2d of a FILL=0.67 run); WORK: where the
# worktrees and runs go (default /tmp/apron-by-commit); DX0 (0.03 m), END_TIME (3.2 s), FILL (0.67, the feed's).
# Cost on the 2-core VM: per commit a build of `flume` (4-8 min) and about 200 s of one thread at dx 0.03 m
# (730 s at 0.02 m). Needs /usr/bin/python3 with h5py and numpy.
# The worktrees stay registered in this checkout, so that a second call reuses their builds: `git worktree
# remove WORK/tree_COMMIT` (or delete WORK, then `git worktree prune`) when done.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
feed=$(realpath "${FEED:?FEED=DIR: the feed2d folder to replay}")
work=${WORK:-/tmp/apron-by-commit}
end_time=${END_TIME:-3.2}
dx0=${DX0:-0.03}
fill=${FILL:-0.67}
[[ $# -gt 0 ]] || { echo "usage: FEED=DIR docs/debris/apron_by_commit.sh COMMIT..." >&2; exit 2; }
mkdir -p "$work"

summary() {  # summary RESULT_DIR LABEL: the containers at 3 s and the apron's gauges to END_TIME, from result.h5
  /usr/bin/python3 - "$1" "$2" "$end_time" <<'EOF'
import sys
import h5py
import numpy as np
run, label, end = sys.argv[1], sys.argv[2], float(sys.argv[3])
f = h5py.File(run + "/result.h5", "r")
print(label)
apron = 0.025  # the apron's height above still water
for g in ("WG3", "WG4"):
    e = f["gauges/%s/elevation" % g][:]
    t = f["gauges/%s/time" % g][:]
    keep = (t >= 2.0) & (t <= end)
    depth = np.clip(e[keep] - apron, 0, None)  # over the apron
    wet = t[np.argmax(e > apron + 0.003)]
    print("  %s depth over the apron: integral %.1f mm s (2 s to %g s), peak %.1f mm at %.2f s; 3 mm deep at %.2f s" % (
        g, 1e3 * np.trapz(depth, t[keep]), end, 1e3 * depth.max(), t[keep][depth.argmax()], wet))
if "debris" not in f:
    sys.exit()
for name in sorted(f["debris"].keys()):
    r = f["debris/%s/resampled" % name]
    t, p, v = r["time"][:], r["position"][:], r["velocity"][:]
    print("  %s travelled %.3f m by 3 s, speed %.2f m/s at 3 s, bottom %+.4f m from its start" % (
        name, np.interp(3.0, t, p[:, 0]) - p[0, 0], np.interp(3.0, t, v[:, 0]), np.interp(3.0, t, p[:, 2]) - p[0, 2]))
EOF
}

for commit in "$@"; do
  tree=$work/tree_$commit
  [[ -d $tree ]] || git -C "$root" worktree add --detach "$tree" "$commit" >/dev/null
  if [[ ! -x $tree/build/bin/flume ]]; then
    cmake -S "$tree" -B "$tree/build" -DFLUME_CUDA=OFF -DFLUME_TESTS=OFF -DCMAKE_BUILD_TYPE=Release \
      >"$work/cmake_$commit.log"
    cmake --build "$tree/build" --target flume -j2 >"$work/build_$commit.log"
  fi
  out=$work/run_${commit}_dx$dx0
  mkdir -p "$out"
  ln -sfn "$feed" "$out/feed2d"
  # The commit's own script and scene: the scene's fields change with the solver.
  FLUME=$tree/build/bin/flume OUT=$out FILL=$fill END_TIME=$end_time DX0=$dx0 THREADS=1 \
    "$tree/docs/debris_waseda_apron.sh" 0x0 >"$out/apron.log" 2>&1
  subject=$(git -C "$root" log -1 --format='%ad, %s' --date=short "$commit" | cut -c1-100)
  summary "$out/apron_0x0" "$commit, dx $dx0 m ($subject)"
done
summary "$feed" "the 2D feed (FEED), its gauges over the same apron"
