#!/usr/bin/env bash
# Stoker's wet-bed bore along the tank (docs/validation.md, section 4): runs scenes/dam_break/stoker_wet_2d.json
# with gauges every 0.1 m from the dam (x = 2 m) to 5.5 m and prints each one's level at 2.5 s (the mean over
# 2.4-2.6 s) against the theory's h2 = 0.11035 m, then the means over the plateau (3.0-3.9 m) and over the
# front zone (4.0-5.0 m; the theory's shock stands at 5.29 m at 2.5 s).
# Usage: docs/validation/stoker_profile.sh [FLUME] [OUT] [--set solver.dx=... --set solver.ppc=...]
set -euo pipefail
flume=${1:-build/bin/flume}; out=${2:-stoker-profile-out}; shift $(( $# < 2 ? $# : 2 ))
gauges=$(awk 'BEGIN { printf "["; for (i = 0; i <= 35; i++) printf "%s{\"name\":\"X%03d\",\"position\":[%.1f],\"rate_hz\":100}", (i ? "," : ""), 200 + 10 * i, 2 + 0.1 * i; printf "]" }')
"$flume" run scenes/dam_break/stoker_wet_2d.json --out "$out" --set "instruments.gauges=$gauges" "$@" >/dev/null
for i in $(seq 0 35); do
  G=$(printf "X%03d" $((200 + 10 * i)))
  h5dump -d /gauges/$G/time -d /gauges/$G/elevation -y -w 0 "$out/result.h5" | awk -v x=$(awk -v i=$i 'BEGIN { print 2 + 0.1 * i }') '
    /DATASET/ {k++} /DATA \{/ {inside=1; next} /\}/ {inside=0}
    inside { gsub(/[^0-9eE.+-]+/, " "); n = split($0, a, " "); for (j = 1; j <= n; j++) { if (k == 1) t[++nt] = a[j]; else e[++ne] = a[j] } }
    END { s = 0; c = 0; for (j = 1; j <= ne; j++) if (t[j] > 2.4 && t[j] < 2.6) { s += e[j]; c++ }
          printf "%.1f %.5f\n", x, s / c }'
done | awk -v h2=0.11035 '
  { printf "x = %.1f m: %.4f m (%+.1f%%)\n", $1, $2, 100 * ($2 - h2) / h2 }
  $1 >= 2.95 && $1 <= 3.95 { p += $2; np++ }  $1 >= 3.95 && $1 <= 5.05 { z += $2; nz++ }
  END { printf "plateau 3.0-3.9 m: %+.1f%%; front zone 4.0-5.0 m: %+.1f%%\n", 100 * (p / np - h2) / h2, 100 * (z / nz - h2) / h2 }'
