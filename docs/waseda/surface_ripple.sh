#!/usr/bin/env bash
# The ripple on the water passing the gauges of `waseda_2d` (docs/surrogates.md, "Where the peaks' scatter comes
# from"): runs the scene to 4.5 s with three 1 kHz gauges at WG2-WG4's positions and prints, for each, the arrival
# (first reading 1 cm above its first, 5 mm at WG4), the peak, and the record's fluctuation about its 0.15 s
# running mean after the arrival: its RMS and the centroid of its spectrum above 5 Hz.
# Usage: docs/waseda/surface_ripple.sh [FLUME] [OUT] [--set solver.dx=... --set solver.ppc=...]
set -euo pipefail
flume=${1:-build/bin/flume}; out=${2:-surface-ripple-out}; shift $(( $# < 2 ? $# : 2 ))
gauges='[{"name":"H2","position":[3.64],"rate_hz":1000,"datum_m":0.23},{"name":"H3","position":[4.69],"rate_hz":1000,"datum_m":0.23},{"name":"H4","position":[6.15],"rate_hz":1000,"datum_m":0.23}]'
"$flume" run scenes/waseda/waseda_2d.json --out "$out" --set solver.end_time=4.5 --set "instruments.gauges=$gauges" "$@" \
  >/dev/null
# /usr/bin/python3: the interpreter with h5py and numpy (a pyenv one on PATH may have neither).
/usr/bin/python3 - "$out/result.h5" <<'PY'
import sys
import h5py
import numpy as np
f = h5py.File(sys.argv[1])
for g, rise in (("H2", 0.01), ("H3", 0.01), ("H4", 0.005)):
    t = f["gauges"][g]["time"][:]
    z = f["gauges"][g]["elevation"][:]
    wet = np.nonzero(z > z[0] + rise)[0]
    if len(wet) == 0:
        print(f"{g}: dry")
        continue
    rate = 1 / (t[1] - t[0])
    seg = z[wet[0]:]
    n = int(0.15 * rate) | 1
    r = (seg - np.convolve(seg, np.ones(n) / n, mode="same"))[n:-n]
    freq = np.fft.rfftfreq(len(r), 1 / rate)
    power = np.abs(np.fft.rfft(r * np.hanning(len(r)))) ** 2
    band = freq > 5
    centroid = (freq[band] * power[band]).sum() / power[band].sum()
    print(f"{g}: arrival {t[wet[0]]:.3f} s, peak {seg.max():.4f} m, ripple RMS {1000 * r.std():.2f} mm, "
          f"centroid {centroid:.1f} Hz")
PY
