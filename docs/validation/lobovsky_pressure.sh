#!/usr/bin/env bash
# Lobovsky et al. (2014), H = 0.3 m: the pressure sensors on the downstream wall against the record (docs/validation.md
# section 3b). Runs scenes/dam_break/lobovsky_2014_2d.json (its probes P1-P4 at z = 3, 15, 30, 80 mm, 10 kHz) and
# prints, per sensor, the mean of p/(rho g H) over windows of t* = t sqrt(g/H) beside the record's (one repetition,
# "peak event 5", 20 kHz), the largest 5 ms mean of the impact (t* < 3), and the RMS over t* 2.4-5.5 of the
# difference of 5 ms means (the reflected bore's return, later, is not scored, as for the gauges).
#   docs/validation/lobovsky_pressure.sh FLUME OUT [--set path=value ...]    (OUT/run is reused if it exists)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
flume=$1
out=$2
shift 2
mkdir -p "$out"
[ -f "$out/run/result.h5" ] || "$flume" run "$root/scenes/dam_break/lobovsky_2014_2d.json" --out "$out/run" --threads 1 "$@" >/dev/null
data=$root/tests/data/validation/lobovsky_2014
[ -d "$root/../shared/validation/lobovsky_2014" ] && data=$root/../shared/validation/lobovsky_2014
/usr/bin/python3 - "$out/run/result.h5" "$data" <<'PY'
import sys
import h5py
import numpy as np
H, g, rho = 0.3, 9.81, 1000.0
ts = np.sqrt(g / H)
files = {"P1": 5, "P2": 4, "P3": 2, "P4": 1}  # Fig18_peak_event_5_sensors_N.dat holds sensor 1, 2, 3, 4 for N = 5, 4, 2, 1
f = h5py.File(sys.argv[1])
def bins(t, p, w=0.005):  # 5 ms means, on t* edges
    k = np.floor(t / w).astype(int)
    u, inv = np.unique(k, return_inverse=True)
    return (u + 0.5) * w * ts, np.bincount(inv, p) / np.bincount(inv)
windows = [(2.4, 2.5), (2.5, 2.8), (2.8, 3.25), (3.25, 4.5), (4.5, 5.5)]
print("sensor  window t*: simulated / measured p/(rho g H)" + " " * 12 + "impact peak (5 ms) sim / meas   RMS 2.4-5.5")
for name, n in files.items():
    m = np.loadtxt("%s/Fig18_peak_event_5_sensors_%d.dat" % (sys.argv[2], n), comments=["#", '"'])
    t = f["/pressure_probes/%s/time" % name][:]
    p = f["/pressure_probes/%s/pressure" % name][:] / (rho * g * H)
    st, sp = bins(t, p)
    mt, mp = bins(m[:, 0] / ts, m[:, 1])
    row = []
    for a, b in windows:
        s_ = sp[(st >= a) & (st < b)].mean()
        m_ = mp[(mt >= a) & (mt < b)].mean()
        row.append("%.2f-%.2f: %.2f / %.2f" % (a, b, s_, m_))
    peak = (sp[st < 3].max(), mp[mt < 3].max())
    common = np.intersect1d(np.round(st, 6), np.round(mt, 6))
    sel_s = np.isin(np.round(st, 6), common) & (st >= 2.4) & (st < 5.5)
    sel_m = np.isin(np.round(mt, 6), common) & (mt >= 2.4) & (mt < 5.5)
    rms = np.sqrt(np.mean((sp[sel_s] - mp[sel_m]) ** 2))
    print("%s  %s   %.2f / %.2f   %.3f" % (name, "  ".join(row), peak[0], peak[1], rms))
PY
