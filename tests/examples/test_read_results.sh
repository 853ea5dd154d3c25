#!/usr/bin/env bash
# examples/read_results.py against the command line: on a small 3D run with a container and on a campaign of
# the analytic Ishigami model, the script must print what `flume gauges` and `flume campaign export` print.
#   test_read_results.sh FLUME SOURCE_DIR
# Exit 77 (skipped) when Debian's python3 lacks h5py or pandas.
set -euo pipefail
flume=$1 src=$2
need="h5py, pandas"
source "$src/tests/examples/setup.sh"

"$flume" run "$src/tests/examples/small_debris_3d.json" --out "$dir/run" --quiet --threads 2 2>"$dir/run.err"
"$flume" gauges "$dir/run" --out "$dir/gauges.svg" | grep -v '^wrote ' >"$dir/flume.txt"

cat >"$dir/spec.json" <<JSON
{"name": "example", "model": "ishigami",
 "parameters": [{"path": "x1", "distribution": {"type": "uniform", "lower": -3.14, "upper": 3.14}},
                {"path": "x2", "distribution": {"type": "uniform", "lower": -3.14, "upper": 3.14}},
                {"path": "x3", "distribution": {"type": "uniform", "lower": -3.14, "upper": 3.14}}],
 "design": {"type": "lhs", "samples": 4}, "seed": 3}
JSON
"$flume" campaign run "$dir/spec.json" --db "$dir/c.db" --workers 2 2>"$dir/campaign.err"
"$flume" campaign export --db "$dir/c.db" --csv - >>"$dir/flume.txt"

"$py" "$src/examples/read_results.py" "$dir/run" --db "$dir/c.db" >"$dir/python.txt" 2>"$dir/python.err"
if ! diff -u "$dir/flume.txt" "$dir/python.txt"; then
  echo "FAILED: examples/read_results.py does not print what flume prints (diff above)"
  exit 1
fi
[[ $(grep -c ' peak ' "$dir/python.txt") -eq 2 ]] || { echo "FAILED: expected two gauge lines"; exit 1; }
[[ $(grep -c '^example,' "$dir/python.txt") -eq 4 ]] || { echo "FAILED: expected four campaign rows"; exit 1; }
echo "ok: $(wc -l <"$dir/python.txt") lines equal"
