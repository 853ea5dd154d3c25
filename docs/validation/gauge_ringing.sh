#!/usr/bin/env bash
# Issue 30's ringing gauges, on Lobovsky et al. (2014)'s dam break, H = 0.3 m (docs/validation.md section 3c).
# Runs scenes/dam_break/lobovsky_2014_2d.json to 2 s with its gauges H1-H4 at 1 kHz, once per variant below, and
# prints per run the fast part of each gauge's record over 1-2 s (the record less its 0.1 s running mean: what
# is quicker than 10 Hz) as an RMS with the frequency of its spectrum's peak above 5 Hz, the same for the
# measured record (3.3 ms samples), and each gauge's normalised RMS error against the record over t* < 11.2.
#   docs/validation/gauge_ringing.sh FLUME OUT [VARIANT...]    (OUT/VARIANT is reused if it exists)
# Variants (default: all): base (the scene as shipped: K 2e6 Pa, CFL 0.4, psi 0.9, APIC, ppc 4, dx 0.01 m),
# K8e6, cfl0.2, cfl0.1, psi0.5, psi1, flip0.9, ppc9, ppc16, dx0.005, dx0.005_ppc9, and in 3D the same tank as a
# strip 6 cm wide between slip walls (docs/validation/lobovsky_2014_3d_strip.json, float) at ppc 8 and 27:
# 3d_ppc8, 3d_ppc27. Cost, one thread on the 2-core VM: 10-35 s each at dx 0.01 m, 70 s at dx 0.005 m, 130 s
# with ppc 9 there; 3D 210 / 470 s.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
flume=$1
out=$2
shift 2
variants=("$@")
[ ${#variants[@]} -eq 0 ] && variants=(base K8e6 cfl0.2 cfl0.1 psi0.5 psi1 flip0.9 ppc9 ppc16 dx0.005 dx0.005_ppc9 3d_ppc8 3d_ppc27)
mkdir -p "$out"
for v in "${variants[@]}"; do
  case $v in
    base) set_args=() ;;
    K8e6) set_args=(--set fluid.bulk_modulus=8e6) ;;
    cfl0.2) set_args=(--set solver.cfl=0.2) ;;
    cfl0.1) set_args=(--set solver.cfl=0.1) ;;
    psi0.5) set_args=(--set fluid.jbar_psi=0.5) ;;
    psi1) set_args=(--set fluid.jbar_psi=1.0) ;;
    flip0.9) set_args=(--set solver.flip=0.9) ;;
    ppc9) set_args=(--set solver.ppc=9) ;;
    ppc16) set_args=(--set solver.ppc=16) ;;
    dx0.005) set_args=(--set solver.dx=0.005) ;;
    dx0.005_ppc9) set_args=(--set solver.dx=0.005 --set solver.ppc=9) ;;
    3d_ppc8) set_args=() ;;
    3d_ppc27) set_args=(--set solver.ppc=27) ;;
    *) echo "unknown variant $v" >&2; exit 2 ;;
  esac
  scene=$root/scenes/dam_break/lobovsky_2014_2d.json
  [[ $v == 3d_* ]] && scene=$root/docs/validation/lobovsky_2014_3d_strip.json
  gauges=()
  for i in 0 1 2 3; do gauges+=(--set "instruments.gauges.$i.rate_hz=1000"); done
  [ -f "$out/$v/result.h5" ] || "$flume" run "$scene" --out "$out/$v" \
    --set solver.end_time=2 "${gauges[@]}" "${set_args[@]}" --threads 1 >"$out/$v.log" 2>&1
done
data=$root/tests/data/validation/lobovsky_2014
[ -d "$root/../shared/validation/lobovsky_2014" ] && data=$root/../shared/validation/lobovsky_2014
/usr/bin/python3 - "$out" "$data" "${variants[@]}" <<'PY'
import json
import sys
import h5py
import numpy as np
out, data, variants = sys.argv[1], sys.argv[2], sys.argv[3:]
H, g = 0.3, 9.81
files = {"H1": "H1_2", "H2": "H2_3", "H3": "H3_3", "H4": "H4_4"}  # the repetitions TNL-SPH compares with
record = {}
for name, tag in files.items():
    d = np.loadtxt("%s/Fig16_WaterLevels_%s.dat" % (data, tag), comments="#")
    record[name] = (d[:, 0] * np.sqrt(H / g), d[:, 1] * H)
def fast(t, h, t0=1.0, t1=2.0):  # RMS (mm) and peak frequency (Hz) of what is quicker than a 0.1 s mean
    k = (t >= t0) & (t <= t1)
    dt = np.median(np.diff(t[k]))
    n = max(3, int(round(0.1 / dt)) | 1)
    x = h[k] - np.convolve(h[k], np.ones(n) / n, mode="same")
    x = x[n:-n]
    spectrum = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    freq = np.fft.rfftfreq(len(x), dt)
    return 1e3 * x.std(), freq[np.argmax(spectrum * (freq > 5))]
def row(label, cells, cost=""):
    print("| %s | %s | %s |" % (label, " | ".join(cells), cost))
print("| run | " + " | ".join("%s: fast RMS 1-2 s (mm) @ Hz / nRMS" % n for n in files) + " | particles, wall |")
print("|---|" + "---|" * (len(files) + 1))
row("the record", ["%.1f @ %.1f" % fast(*record[n]) for n in files])
for v in variants:
    f = h5py.File("%s/%s/result.h5" % (out, v), "r")
    cells = []
    for n in files:
        t, e = f["gauges/%s/time" % n][:], f["gauges/%s/elevation" % n][:]
        tr, hr = record[n]
        k = tr <= t[-1]
        nrms = np.sqrt(np.mean((np.interp(tr[k], t, e) - hr[k]) ** 2)) / hr[k].max()
        cells.append("%.1f @ %.1f / %.3f" % (fast(t, e) + (nrms,)))
    cost = json.load(open("%s/%s/run.json" % (out, v)))["cost"]
    row(v, cells, "%d, %.0f s" % (cost["particles"], cost["wall_s"]))
PY
