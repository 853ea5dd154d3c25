#!/usr/bin/env bash
# Free efflux under a vertical sluice gate (docs/validation.md, section 6c): the contracted jet against
# potential-flow theory. 2D: a reservoir 2 m long, 0.5 m deep, drains under a sharp-edged slip gate 0.04 m thick
# with an opening a = 0.1 m onto a dry floor that ends 0.76 m downstream in a pit, so the jet stays free (no
# tailwater). Until the drawdown wave returns from the back wall (about 1.7 s) the water approaching the gate is
# a steady stream, read by a section 0.6 m upstream of the gate (depth h1, speed U1: energy head E = h1 + U1^2 /
# 2 g); a section 0.16 m past the gate (the vena contracta lies about a / Cc downstream) reads the jet's depth and
# speed. Theory for a vertical sharp-edged gate in free flow (von Mises; Fangmeier & Strelkoff 1968; Montes
# 1997; Belaud et al. 2009, J. Hydraul. Eng. 135(12)): the jet contracts to Cc a, Cc 0.60-0.61 at these
# openings (a / E about 0.25), and loses almost no head, so q = Cc a sqrt(2 g (E - Cc a)). The script prints
# means over 0.5-1.5 s: the jet's depth over a (Cc as read, to within a particle spacing), its speed over
# sqrt(2 g (E - depth)) (the velocity coefficient Cv: 1 without loss), and q over the theory's at Cc = 0.605.
# Usage: docs/validation/sluice_gate.sh FLUME OUT [--set path=value ...]
set -euo pipefail
flume=$1; out=$2
shift 2
mkdir -p "$out"
# /usr/bin/python3: the interpreter with h5py and numpy.
/usr/bin/python3 - "$out" <<'PY'
import json, sys

out = sys.argv[1]
slip = lambda name, p, n: {"name": name, "type": "half_space", "point": p, "normal": n, "condition": "slip"}
box = lambda name, lo, hi: {"name": name, "type": "box", "lo": lo, "hi": hi, "condition": "slip"}
Lr, H0, a, t_gate, sill_end = 2.0, 0.5, 0.1, 0.04, 2.8
scene = {"name": "sluice_gate_free_efflux", "dimension": 2,
         "domain": {"lo": [-0.1, -0.7], "hi": [3.9, 1.1], "walls": "slip"},
         "solver": {"dx": 0.02, "ppc": 4, "cfl": 0.4, "precision": "float", "end_time": 1.5},
         "fluid": {"density": 1000, "bulk_modulus": 2e6, "gamma": 7.0, "viscosity": 1e-3, "jbar_psi": 0.9},
         "water": [{"lo": [0.0, 0.0], "hi": [Lr, H0]}],
         "boundaries": [slip("back", [0, 0], [1, 0]),
                        box("floor", [-0.2, -0.8], [sill_end, 0.0]),
                        box("gate", [Lr, a], [Lr + t_gate, 1.2])],
         "instruments": {"sections": [{"name": "up", "x_m": Lr - 0.6, "rate_hz": 200},
                                      {"name": "jet", "x_m": Lr + t_gate + 0.16, "rate_hz": 200}],
                         "diagnostics_rate_hz": 20}}
json.dump(scene, open(f"{out}/scene.json", "w"), indent=1)
PY
/usr/bin/time -f "%U" -o "$out/cpu_s" "$flume" run "$out/scene.json" --out "$out/run" -q "$@"
/usr/bin/python3 - "$out" <<'PY'
import json, sys
import h5py
import numpy as np

out = sys.argv[1]
a, g = 0.1, 9.81
cpu = open(f"{out}/cpu_s").read().strip()
dx = json.load(open(f"{out}/run/run.json"))["scene_json"]["solver"]["dx"]
with h5py.File(f"{out}/run/result.h5", "r") as r:
    read = lambda name: [r[f"sections/{name}/{k}"][:] for k in ("time", "depth", "velocity")]
    t, d, v = read("jet")
    tu, h1, U1 = read("up")
keep = (t >= 0.5) & (t <= 1.5)
t, d, v = t[keep], d[keep], v[keep]
E = np.interp(t, tu, h1 + U1**2 / (2 * g))
q = d * v
cc = 0.605
q_theory = cc * a * np.sqrt(2 * g * (E - cc * a))
print(f"dx {dx}: jet depth / a {d.mean() / a:.3f}, Cv {(v / np.sqrt(2 * g * (E - d))).mean():.3f}, "
      f"q / q_theory {(q / q_theory).mean():.3f}, q {q.mean():.4f} m^2/s, head E {E.mean():.3f} m; {cpu} CPU-s")
PY
