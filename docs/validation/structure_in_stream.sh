#!/usr/bin/env bash
# Water against a structure in 3D at coarse spacings (docs/validation.md, section 6b): how much the solver's
# transfer (APIC, or FLIP blended by solver.flip) makes a structure hold the flow back. Two scenes, written into
# OUT and run by FLUME with the overrides given:
#   pier: a uniform stream 0.12 m deep at 2 m/s (Froude 1.8; an inflow plane at x = 0.3 m) in a slip channel
#         0.8 m wide, past a square pier 0.1 m wide at x = 1.5 m; 1.6 s. Prints the pier's drag (its load cell,
#         mean over 1.2-1.6 s, the flow steady) and the depth 0.1 and 0.3 m behind it.
#   dambreak: 0.6 x 0.6 x 0.4 m of water released in a 2 x 0.6 m slip tank onto a box 0.12 x 0.24 x 0.12 m at
#         x = 1.30 m; 1.2 s. Prints the box's mean drag over 0.6-1.2 s and the highest level 0.10 m behind it.
# Usage: docs/validation/structure_in_stream.sh FLUME OUT pier|dambreak [--set path=value ...]
set -euo pipefail
flume=$1; out=$2; case_=$3
shift 3
mkdir -p "$out"
# /usr/bin/python3: the interpreter with h5py and numpy.
/usr/bin/python3 - "$out" "$case_" <<'PY'
import json, sys
import h5py

out, case_ = sys.argv[1], sys.argv[2]
fluid = {"density": 1000, "bulk_modulus": 2e6, "gamma": 7.0, "viscosity": 1e-3, "jbar_psi": 0.9}
slip = lambda name, p, n: {"name": name, "type": "half_space", "point": p, "normal": n, "condition": "slip"}
if case_ == "pier":
    h1, u1, W, P, dx = 0.12, 2.0, 0.8, 0.1, 0.04
    with h5py.File(f"{out}/stream.h5", "w") as f:
        g = f.create_group("sections/stream")
        g["time"], g["depth"], g["velocity"] = [0.0, 100.0], [h1, h1], [u1, u1]
        g.attrs["x_m"], g.attrs["floor_m"] = 0.3, 0.0
    lo, hi = [-0.2, -W / 2 - 0.12, -0.08], [2.6, W / 2 + 0.12, 0.5]
    scene = {"name": "pier_in_stream", "dimension": 3, "domain": {"lo": lo, "hi": hi, "walls": "slip"},
             "solver": {"dx": dx, "ppc": 8, "cfl": 0.4, "precision": "float", "end_time": 1.6}, "fluid": fluid,
             # A scene needs water to start with: a puddle at the far end, which the stream sweeps along.
             "water": [{"lo": [2.4, -W / 2, 0.0], "hi": [2.5, W / 2, 0.02]}],
             "inflow": {"record": f"{out}/stream.h5", "section": "stream", "x_m": 0.3, "y_m": [-W / 2, W / 2]},
             "boundaries": [slip("floor", [0, 0, 0], [0, 0, 1]), slip("left", [0, -W / 2, 0], [0, 1, 0]),
                            slip("right", [0, W / 2, 0], [0, -1, 0]),
                            {"name": "pier", "type": "box", "lo": [1.5, -P / 2, lo[2]], "hi": [1.5 + P, P / 2, hi[2]],
                             "condition": "slip"}],
             "instruments": {"gauges": [{"name": "wake1", "position": [1.5 + P + 0.1, 0.0], "rate_hz": 100},
                                        {"name": "wake3", "position": [1.5 + P + 0.3, 0.0], "rate_hz": 100}],
                             "loads": [{"name": "pier", "boundary": "pier", "rate_hz": 100}],
                             "diagnostics_rate_hz": 20}}
elif case_ == "dambreak":
    L, W = 2.0, 0.6
    scene = {"name": "dam_break_onto_box", "dimension": 3,
             "domain": {"lo": [-0.08, -0.08, -0.08], "hi": [L + 0.08, W + 0.08, 0.8], "walls": "slip"},
             "solver": {"dx": 0.04, "ppc": 8, "cfl": 0.4, "precision": "float", "end_time": 1.2}, "fluid": fluid,
             "water": [{"lo": [0, 0, 0], "hi": [0.6, W, 0.4]}],
             "boundaries": [slip("floor", [0, 0, 0], [0, 0, 1]), slip("back", [0, 0, 0], [1, 0, 0]),
                            slip("end", [L, 0, 0], [-1, 0, 0]), slip("s0", [0, 0, 0], [0, 1, 0]),
                            slip("s1", [0, W, 0], [0, -1, 0]),
                            {"name": "box", "type": "box", "lo": [1.30, 0.18, -0.1], "hi": [1.42, 0.42, 0.12],
                             "condition": "slip"}],
             "instruments": {"gauges": [{"name": "behind", "position": [1.52, 0.30], "rate_hz": 200}],
                             "loads": [{"name": "box", "boundary": "box", "rate_hz": 200}],
                             "diagnostics_rate_hz": 20}}
else:
    sys.exit("case: pier or dambreak")
json.dump(scene, open(f"{out}/scene.json", "w"), indent=1)
PY
/usr/bin/time -f "%U" -o "$out/cpu_s" "$flume" run "$out/scene.json" --out "$out/run" -q "$@"
/usr/bin/python3 - "$out" "$case_" <<'PY'
import sys
import h5py

out, case_ = sys.argv[1], sys.argv[2]
cpu = open(f"{out}/cpu_s").read().strip()
with h5py.File(f"{out}/run/result.h5", "r") as r:
    def mean(path, col, a, b):
        t, v = r[path + "/time"][:], r[path + ("/force" if col is not None else "/elevation")][:]
        v = v[:, col] if col is not None else v
        return v[(t >= a) & (t <= b)].mean()
    if case_ == "pier":
        print(f"pier drag {mean('loads/pier', 0, 1.2, 1.6):.1f} N; depth 0.1 / 0.3 m behind it "
              f"{mean('gauges/wake1', None, 1.2, 1.6):.3f} / {mean('gauges/wake3', None, 1.2, 1.6):.3f} m; {cpu} CPU-s")
    else:
        e = r["gauges/behind/elevation"][:]
        print(f"box drag {mean('loads/box', 0, 0.6, 1.2):.1f} N (0.6-1.2 s); highest level 0.1 m behind it "
              f"{e.max():.3f} m; {cpu} CPU-s")
PY
