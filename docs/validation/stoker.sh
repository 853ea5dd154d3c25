#!/usr/bin/env bash
# Stoker's wet-bed dam break (docs/validation.md, section 4): runs scenes/dam_break/stoker_wet_2d.json and prints, at
# each gauge, the bore's arrival (first reading above (h1 + h2) / 2), the mean level 0.15-0.45 s after it (inside
# the front's transition) and the plateau's mean level from 0.84 s after the theory's arrival to 2.8 s (where the
# window is not empty), against the shallow-water solution (h0 = 0.2 m, h1 = 0.05 m: h2 = 0.11035 m, bore speed 1.31728 m/s, dam at x = 2 m).
# Usage: docs/validation/stoker.sh [FLUME] [OUT] [--set solver.dx=...]
set -euo pipefail
flume=${1:-build/bin/flume}; out=${2:-stoker-out}; shift $(( $# < 2 ? $# : 2 ))
"$flume" run scenes/dam_break/stoker_wet_2d.json --out "$out" "$@" >/dev/null
for G in G3 G4 G5; do
  h5dump -d /gauges/$G/time -d /gauges/$G/elevation -y -w 0 "$out/result.h5" | awk -v G=$G '
    /DATASET/ {k++} /DATA \{/ {inside=1; next} /\}/ {inside=0}
    inside { gsub(/[^0-9eE.+-]+/, " "); n = split($0, a, " "); for (i = 1; i <= n; i++) { if (k == 1) t[++nt] = a[i]; else e[++ne] = a[i] } }
    END { x = substr(G, 2) + 0; h1 = 0.05; h2 = 0.11035; ta = -1
      for (i = 1; i <= ne; i++) if (ta < 0 && e[i] > (h1 + h2) / 2) ta = t[i]
      s = 0; c = 0; for (i = 1; i <= ne; i++) if (t[i] > ta + 0.15 && t[i] < ta + 0.45) { s += e[i]; c++ }
      printf "%s (x = %g m): arrival %.3f s (Stoker %.3f), level behind the bore %.4f m (Stoker %.4f, %+.1f%%)",
             G, x, ta, (x - 2) / 1.31728, s / c, h2, 100 * (s / c - h2) / h2
      t0 = (x - 2) / 1.31728 + 0.84; s = 0; c = 0
      for (i = 1; i <= ne; i++) if (t[i] >= t0 && t[i] <= 2.8) { s += e[i]; c++ }
      if (c > 0) printf ", plateau from %.2f s %.4f m (%+.1f%%)", t0, s / c, 100 * (s / c - h2) / h2
      printf "\n" }'
done
