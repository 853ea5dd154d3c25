#!/usr/bin/env bash
# Ritter's dry-bed dam break (docs/validation.md, section 4b): runs scenes/dam_break/ritter_dry_2d.json and prints
# the section's row: RMS of the depth against the shallow-water solution at x = 8-12 m over 1-3 s where it gives
# more than 0.05 m (what Ritter.DryBedWaveDownstreamOfTheDamWithinHalfAParticleSpacing bounds), the same at 6 m
# with its mean error, and when the 5 mm contour reaches x = 16 m (theory 2.56 s).
# Usage: docs/validation/ritter.sh [FLUME] [OUT] [--set solver.dx=...]   (FLUME "-": compare OUT as it is)
#        SCENE (environment): another scene with the same gauges X6-X16, e.g. the tank extruded to 3D.
set -euo pipefail
flume=${1:-build/bin/flume}; out=${2:-ritter-out}; shift $(( $# < 2 ? $# : 2 ))
[ "$flume" = "-" ] || "$flume" run "${SCENE:-scenes/dam_break/ritter_dry_2d.json}" --out "$out" "$@" >/dev/null
# /usr/bin/python3: the interpreter with h5py and numpy.
/usr/bin/python3 - "$out/result.h5" <<'PY'
import sys
import h5py
import numpy as np

g, h0, x0 = 9.81, 0.4, 7.55
c0 = np.sqrt(g * h0)


def ritter(x, t):
    xi = (x - x0) / t
    return np.where(xi <= -c0, h0, np.where(xi >= 2 * c0, 0.0, (2 * c0 - xi) ** 2 / (9 * g)))


with h5py.File(sys.argv[1], "r") as h5:
    def read(x):
        return h5[f"gauges/X{x}/time"][:], h5[f"gauges/X{x}/elevation"][:]

    def errors(x):
        t, h = read(x)
        exact = ritter(x, np.maximum(t, 1e-9))  # the first sample is at t = 0
        keep = (t >= 1.0) & (t <= 3.0) & (exact >= 0.05)
        d = h[keep] - exact[keep]
        return 1e3 * np.sqrt(np.mean(d * d)), 1e3 * np.mean(d)

    downstream = " / ".join(f"{errors(x)[0]:.1f}" for x in range(8, 13))
    rms6, mean6 = errors(6)
    t, h = read(16)
    wet = np.nonzero(h >= 0.005)[0]
    contour = f"{t[wet[0]]:.2f} s" if wet.size else "not reached"
    print("| RMS at x = 8 / 9 / 10 / 11 / 12 m (mm) | at 6 m (mm, mean error) | 5 mm contour at x = 16 m |")
    print(f"| {downstream} | {rms6:.1f} ({mean6:+.1f}) | {contour} |")
PY
