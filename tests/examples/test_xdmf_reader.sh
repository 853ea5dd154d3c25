#!/usr/bin/env bash
# A run with particle snapshots and a container is opened by an XDMF reader of a Debian package, and what it
# reads matches result.h5: ParaView's own (pvpython) where it is on PATH, else meshio's (python3-meshio),
# else skipped with the reason (exit 77).
#   test_xdmf_reader.sh FLUME SOURCE_DIR     (FLUME_XDMF_READER=meshio forces meshio where pvpython is installed)
set -euo pipefail
flume=$1 src=$2
need="h5py, numpy"
source "$src/tests/examples/setup.sh"
end=0.3 rate=20
"$flume" run "$src/tests/examples/small_debris_3d.json" --out "$dir/run" --quiet --threads 2 \
  --set instruments.snapshot_rate_hz=$rate --set solver.end_time=$end 2>"$dir/run.err"
if [ "${FLUME_XDMF_READER:-}" != meshio ] && command -v pvpython >/dev/null; then
  pvpython "$src/tests/examples/read_xdmf_paraview.py" "$dir/run" $end $rate
elif "$py" -c "import meshio" 2>/dev/null; then
  "$py" "$src/tests/examples/read_xdmf_meshio.py" "$dir/run" $end $rate
else
  echo "skipped: no XDMF reader: neither pvpython (Debian paraview) on PATH nor meshio in $py (Debian python3-meshio)"
  exit 77
fi
