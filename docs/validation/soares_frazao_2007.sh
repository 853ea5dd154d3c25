#!/usr/bin/env bash
# Soares-Frazao & Zech (2007) dam break against an isolated building (tests/data/validation/soares_frazao_2007/):
# runs scenes/validation/soares_frazao_2007_3d.json and prints, at each gauge G1-G6, the normalised RMS error of the
# water depth: RMS(sim - measured) / max(measured), over the measured record's times (sim interpolated linearly to
# them) that the run covers; the span used is printed, so a shortened run (--set solver.end_time=...) says so.
# Usage: docs/validation/soares_frazao_2007.sh [FLUME] [OUT] [--set solver.dx=... --backend cuda ...]
#        FLUME = "-" compares an existing OUT/result.h5 without running.
set -euo pipefail
flume=${1:-build/bin/flume}; out=${2:-soares-frazao-out}; shift $(( $# < 2 ? $# : 2 ))
if [ "$flume" != "-" ]; then
  "$flume" run scenes/validation/soares_frazao_2007_3d.json --out "$out" "$@" >/dev/null
fi
# /usr/bin/python3: the interpreter with h5py and numpy (the pyenv one on PATH has neither).
/usr/bin/python3 - "$out/result.h5" tests/data/validation/soares_frazao_2007/gauges_depth.csv <<'PY'
import sys
import h5py
import numpy as np

result, measured_csv = sys.argv[1], sys.argv[2]
measured = np.genfromtxt(measured_csv, delimiter=",", names=True)
with h5py.File(result, "r") as h5:
    for name in measured.dtype.names[1:]:
        t_meas, h_meas = measured["time_s"], measured[name]
        if f"gauges/{name}" not in h5:
            print(f"{name}: no gauge of that name in {result}")
            continue
        t_sim = h5[f"gauges/{name}/time"][:]
        h_sim = h5[f"gauges/{name}/elevation"][:]
        keep = (t_meas >= t_sim[0]) & (t_meas <= t_sim[-1]) & np.isfinite(h_meas)
        if not keep.any():
            print(f"{name}: the run's record ({t_sim[0]:.2f}-{t_sim[-1]:.2f} s) misses the measured times")
            continue
        err = np.interp(t_meas[keep], t_sim, h_sim) - h_meas[keep]
        scale = h_meas.max()
        print(f"{name}: nRMS {np.sqrt(np.mean(err ** 2)) / scale:.3f} over {t_meas[keep][0]:.2f}-{t_meas[keep][-1]:.2f} s "
              f"({keep.sum()} samples; measured max {scale:.3f} m, mean error {err.mean():+.4f} m)")
PY
