#!/usr/bin/env bash
# Issue 30: pressure probes up a wall against the wall's load cell (docs/results.md, "Against the load cell").
# A 2D dam break, 0.2 x 0.2 m of water 0.4 m from a slip wall, dx = 1 cm; 40 probes 1 cm apart up the wall,
# their pressures times 1 cm summed, against the load cell's force (N/m), as 0.1 s means and the impulse.
#   docs/pressure_probes_wall.sh [FLUME] [OUT] [METHOD]     METHOD: mpm (default) or sph
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flume=${1:-$root/build/bin/flume}
out=${2:-$(mktemp -d)}
method=${3:-mpm}
mkdir -p "$out"
probes=$(/usr/bin/python3 -c 'import json; print(json.dumps([{"name": "z%02d" % k, "position": [0.6, 0.005 + 0.01 * k], "normal": [-1, 0]} for k in range(40)]))')
cat > "$out/wall.json" <<JSON
{"name": "dam_wall_probes", "dimension": 2,
 "domain": {"lo": [-0.05, -0.05], "hi": [0.65, 0.4], "walls": "slip"},
 "solver": {"dx": 0.01, "ppc": 4, "precision": "float", "end_time": 0.6},
 "fluid": {"bulk_modulus": 2.0e5, "jbar_psi": 0.9},
 "water": [{"lo": [0, 0], "hi": [0.2, 0.2]}],
 "boundaries": [
   {"name": "floor", "type": "half_space", "point": [0, 0], "normal": [0, 1], "condition": "slip"},
   {"name": "back", "type": "half_space", "point": [0, 0], "normal": [1, 0], "condition": "slip"},
   {"name": "wall", "type": "half_space", "point": [0.6, 0], "normal": [-1, 0], "condition": "slip"}],
 "instruments": {"loads": [{"name": "wall", "boundary": "wall", "rate_hz": 1000}], "pressure_probes": $probes}}
JSON
"$flume" run "$out/wall.json" --out "$out/run" --threads 1 --set solver.method=$method >/dev/null
/usr/bin/python3 - "$out/run/result.h5" <<'PY'
import sys
import h5py
import numpy as np
f = h5py.File(sys.argv[1])
t = f["/loads/wall/time"][:]
load = f["/loads/wall/force"][:, 0]  # the water's force on the wall, +x
probes = sum(f["/pressure_probes/z%02d/pressure" % k][:] for k in range(40)) * 0.01
dt = np.diff(t)
for a in np.arange(0.0, 0.6, 0.1):
    m = (t > a + 1e-9) & (t <= a + 0.1 + 1e-9)
    print("%.1f-%.1f s: load %.1f N/m, probes %.1f N/m" % (a, a + 0.1, load[m].mean(), probes[m].mean()))
print("impulse: load %.2f, probes %.2f N s/m" % ((load[1:] * dt).sum(), (probes[1:] * dt).sum()))
PY
