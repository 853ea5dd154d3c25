#!/usr/bin/env bash
# A bore reflected from a wall into a steady stream (docs/validation.md, section 4c): a 2D channel fed through an
# inflow plane at x = 0.3 m with a uniform stream (depth H1, velocity U1; a synthetic section record written into
# OUT), a slip end wall at x = 8 m. The stream strikes the wall and a bore runs back upstream into it. Against the
# shallow-water jump (Rankine-Hugoniot, the wall's water at rest): h1 (u1 + w) u1 = g (h2^2 - h1^2) / 2 and
# w = h1 u1 / (h2 - h1), with h1 and u1 as the run's own section at x = 4 m reads them in the second before the
# bore reaches it. Prints the stream, the jump's h2 and w, the plateau (gauges at 6.5-7.5 m over 10-12 s, the bore
# 1.5 m or more upstream of them), the level 0.3-1.0 s behind the toe at x = 5 m, and the bore's speed (a line
# through its arrivals, first reading above (h1 + h2) / 2, at x = 4-6.5 m).
# Usage: docs/validation/reflected_bore.sh [FLUME] [OUT] [H1] [U1] [--set solver.dx=...]
set -euo pipefail
flume=${1:-build/bin/flume}; out=${2:-reflected-bore-out}; h1=${3:-0.04}; u1=${4:-2.0}
shift $(( $# < 4 ? $# : 4 ))
mkdir -p "$out"
# /usr/bin/python3: the interpreter with h5py and numpy.
/usr/bin/python3 - "$out" "$h1" "$u1" <<'PY'
import json, sys
import h5py
import numpy as np

out, h1, u1 = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
with h5py.File(f"{out}/stream.h5", "w") as f:
    g = f.create_group("sections/stream")
    g["time"], g["depth"], g["velocity"] = [0.0, 100.0], [h1, h1], [u1, u1]
    g.attrs["x_m"], g.attrs["floor_m"] = 0.3, 0.0
gauges = [{"name": f"G{x:.1f}", "position": [x], "rate_hz": 100} for x in np.arange(4.0, 7.51, 0.5)]
scene = {
    "name": "reflected_bore_2d", "dimension": 2,
    "domain": {"lo": [-0.2, -0.1], "hi": [8.1, 0.6], "walls": "slip"},
    "solver": {"dx": 0.02, "ppc": 4, "cfl": 0.4, "precision": "float", "end_time": 12.0},
    "fluid": {"density": 1000, "bulk_modulus": 2e6, "gamma": 7.0, "viscosity": 1e-3, "jbar_psi": 0.9},
    # A scene needs water to start with: a puddle against the end wall, which the stream sweeps up.
    "water": [{"lo": [7.9, 0.0], "hi": [8.0, 0.02]}],
    "inflow": {"record": f"{out}/stream.h5", "section": "stream", "x_m": 0.3},
    "boundaries": [
        {"name": "floor", "type": "half_space", "point": [0, 0], "normal": [0, 1], "condition": "slip"},
        {"name": "end_wall", "type": "half_space", "point": [8.0, 0], "normal": [-1, 0], "condition": "slip"},
    ],
    "instruments": {"gauges": gauges, "sections": [{"name": "S4", "x_m": 4.0, "rate_hz": 100}],
                    "diagnostics_rate_hz": 20},
}
json.dump(scene, open(f"{out}/scene.json", "w"), indent=1)
PY
/usr/bin/time -f "%U" -o "$out/cpu_s" "$flume" run "$out/scene.json" --out "$out/run" -q "$@"
/usr/bin/python3 - "$out" <<'PY'
import sys
import h5py
import numpy as np

out, g = sys.argv[1], 9.80665

def jump(h1, u1):  # the reflected bore's depth h2 and speed w (bisection on the momentum balance)
    f = lambda h2: h1 * (u1 + h1 * u1 / (h2 - h1)) * u1 - g / 2 * (h2 ** 2 - h1 ** 2)
    a, b = h1 * 1.0001, 10.0
    for _ in range(200):
        m = (a + b) / 2
        a, b = (a, m) if f(a) * f(m) <= 0 else (m, b)
    h2 = (a + b) / 2
    return h2, h1 * u1 / (h2 - h1)

with h5py.File(f"{out}/run/result.h5", "r") as r:
    t, d, v = (r[f"sections/S4/{k}"][:] for k in ("time", "depth", "velocity"))
    gauge = {x: (r[f"gauges/G{x:.1f}/time"][:], r[f"gauges/G{x:.1f}/elevation"][:]) for x in np.arange(4.0, 7.51, 0.5)}
steady = np.median(d[(t > 6) & (t < 8)])
toe = t[np.nonzero((t > 6) & (d > 1.5 * steady))[0][0]]
w_ = (t > toe - 1.2) & (t < toe - 0.2)
h1 = d[w_].mean()
u1 = (d[w_] * v[w_]).sum() / d[w_].sum()
h2, w = jump(h1, u1)
xs = [4.0, 4.5, 5.0, 5.5, 6.0, 6.5]
arrivals = [tg[np.nonzero((tg > 2) & (e > (h1 + h2) / 2))[0][0]] for tg, e in (gauge[x] for x in xs)]
speed = abs(1 / np.polyfit(xs, arrivals, 1)[0])
plateau = np.mean([e[(tg >= 10) & (tg <= 12)].mean() for tg, e in (gauge[x] for x in (6.5, 7.0, 7.5))])
tg, e = gauge[5.0]
behind = e[(tg > arrivals[2] + 0.3) & (tg < arrivals[2] + 1.0)].mean()
cpu = open(f"{out}/cpu_s").read().strip()
print(f"stream h1 {h1:.4f} m, u1 {u1:.3f} m/s (Froude {u1 / np.sqrt(g * h1):.2f}); jump h2 {h2:.4f} m, w {w:.3f} m/s; "
      f"plateau {plateau:.4f} m ({100 * (plateau / h2 - 1):+.1f} %); 0.3-1.0 s behind the toe at 5 m {behind:.4f} m "
      f"({100 * (behind / h2 - 1):+.1f} %); bore speed {speed:.3f} m/s ({100 * (speed / w - 1):+.1f} %); {cpu} CPU-s")
PY
