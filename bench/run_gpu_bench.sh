#!/usr/bin/env bash
# CUDA backend on a GPU machine, one prepared run (issue 25): every CPU-against-GPU reference run (test_cuda's
# Cuda.* tests, the CPU solver in the same program), then the speed as particle-steps per second of the 3D dam
# break of about one million particles in float and double, and of the same dam break at dx 4.5 mm, 21.9 million
# particles (LARGE_DX sets it), in float and double. Prints a Markdown table for docs/benchmarks.md with the device
# named.
#
# The GPU machine (tool `device`, H100/H200) has nvcc and CMake but not this project's libraries, so programs
# built here travel with theirs. The usual way, one call (flume, test_cuda, test_checkpoint and
# test_conservation in one xz archive, 53 MB):
#
#   here:   cmake --build build -j2 && bench/run_gpu_bench.sh flume-bundle build    # writes .gpu-flume/
#   device: run(command="bench/run_gpu_bench.sh device", carry=[".gpu-flume"], timeout_s=560)
#             the reference tests, the benchmark, then whole `flume run --backend cuda` runs (below)
#           run(command="bench/run_gpu_bench.sh device-checks", carry=[".gpu-flume"], timeout_s=440)
#             every device test (checkpoint and conservation twins too), the 2D basin at dx 0.01 m and the
#             Soares-Frazao case at three dx (validation-runs)
#
# The older, smaller bundle (test_cuda alone, into .gpu/): `bench/run_gpu_bench.sh bundle [BUILD_DIR]`, then
# run(command="bench/run_gpu_bench.sh", carry=[".gpu"]); STEPS=400 ... bench-only for the benchmark alone.
# Where a full build sits next to a GPU, FLUME=build/bin/flume TEST_CUDA=build/bin/test_cuda adds
# `flume bench --backend cuda` figures.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
mode=${1:-all}
tests_failed=0

# On the device: flume's archive (flume-bundle) unpacked into $fl, and $out where results go.
unpack_flume() {
  fl=$(mktemp -d)
  tar -C "$fl" -xJf .gpu-flume/flume.tar.xz
  out=${OUT:-$(mktemp -d)}
}

if [[ $mode == bundle ]]; then
  build=${2:-$root/build-cuda}
  rm -rf .gpu
  mkdir -p .gpu/bin .gpu/lib
  exclude=$(git rev-parse --git-path info/exclude)
  mkdir -p "$(dirname "$exclude")"
  grep -qx '/.gpu/' "$exclude" 2>/dev/null || echo '/.gpu/' >>"$exclude"
  cp "$build/bin/test_cuda" .gpu/bin/
  # Every shared library but the C library's own (the device's glibc is newer, and binaries built against an
  # older one run on it) and the CUDA driver (the device's own must be used).
  for exe in .gpu/bin/*; do
    ldd "$exe" | awk '/=> \// {print $3}'
  done | sort -u | grep -vE '/(libc|libm|libdl|libpthread|librt|libresolv|ld-linux[^/]*|libcuda)\.so' |
    while read -r lib; do cp -L "$lib" .gpu/lib/; done
  du -sh .gpu
  echo "bundled into $root/.gpu: carry it with run(..., carry=[\".gpu\"]) (64 MiB at most)"
  exit 0
fi

# Whole runs through `flume run --backend cuda` (the command line users call, debris included): flume and its
# libraries are 170 MB, over what the device tool carries, so they travel as one xz archive (about 45 MB):
#   here:   bench/run_gpu_bench.sh flume-bundle [BUILD_DIR]          # writes .gpu-flume/flume.tar.xz
#   device: run(command="bench/run_gpu_bench.sh flume-runs", carry=[".gpu-flume"])
# The runs: the three-container strip at its shipped dx on the GPU and on the device's CPU cores, in double (the
# backends must agree until the containers' contacts amplify round-off) and in float (twice on the GPU: its
# atomics' order changes from run to run, so two GPU runs show the spread round-off alone gives), at half that
# dx on the GPU, and the whole basin (5x2 columns) at its shipped dx. Each prints its wall time and debris metrics; run.json files go to $OUT when set.
if [[ $mode == flume-bundle ]]; then
  build=${2:-$root/build}
  stage=$(mktemp -d)
  mkdir -p "$stage/bin" "$stage/lib" .gpu-flume
  exclude=$(git rev-parse --git-path info/exclude)
  grep -qx '/.gpu-flume/' "$exclude" 2>/dev/null || echo '/.gpu-flume/' >>"$exclude"
  # flume, test_cuda, and the test programs whose device tests (Checkpoint.CudaResumed*, Conservation.Cuda*)
  # need more than test_cuda's libraries.
  cp "$build/bin/flume" "$build/bin/test_cuda" "$build/bin/test_checkpoint" "$build/bin/test_conservation" \
    "$stage/bin/"
  strip "$stage"/bin/*
  ldd "$stage"/bin/* | awk '/=> \// {print $3}' |
      grep -vE '/(libc|libm|libdl|libpthread|librt|libresolv|ld-linux[^/]*|libcuda)\.so' | sort -u |
    while read -r lib; do cp -L "$lib" "$stage/lib/"; done
  tar -C "$stage" -cf - . | xz -T2 -9e >.gpu-flume/flume.tar.xz
  rm -rf "$stage"
  du -sh .gpu-flume
  exit 0
fi
# The whole device check in one call (the archive holds test_cuda too): the tests and the benchmark with flume
# named, then the whole runs, each stage under its own limit, the log written to $OUT:
#   device: run(command="bench/run_gpu_bench.sh device", carry=[".gpu-flume"], timeout_s=560)
if [[ $mode == device ]]; then
  unpack_flume
  set +e
  LD_LIBRARY_PATH=$fl/lib FLUME=$fl/bin/flume TEST_CUDA=$fl/bin/test_cuda timeout "${BENCH_LIMIT:-330}" "$0" all 2>&1 |
    tee "$out/bench.log"
  timeout "${RUNS_LIMIT:-200}" "$0" flume-runs 2>&1 | tee "$out/runs.log"
  exit 0
fi
# The 3D validation case (docs/validation.md, section 6) at several resolutions on the GPU, for the probes'
# errors and the cost of each: result.h5 and run.json of each to $OUT, read back here with
# `docs/validation/soares_frazao_2007.sh - DIR` (DIR holding that result.h5).
#   device: run(command="SF_DX='0.05 0.0375' SF_END=10 bench/run_gpu_bench.sh validation-runs", carry=[".gpu-flume"])
# Every device test (test_cuda's, then the checkpoint and conservation programs' device twins), then the 2D
# basin at dx 0.01 m over 8 s (the quay crossing of docs/validation.md, section 1), then validation-runs:
#   device: run(command="bench/run_gpu_bench.sh device-checks", carry=[".gpu-flume"], timeout_s=440)
if [[ $mode == device-checks ]]; then
  unpack_flume
  set +e
  (
    export LD_LIBRARY_PATH=$fl/lib FLUME_EXE=$fl/bin/flume FLUME_SOURCE_DIR=$root
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
    timeout 150 "$fl/bin/test_cuda" --gtest_color=no --gtest_filter='Cuda.*:CudaCli.*'
    timeout 60 "$fl/bin/test_checkpoint" --gtest_color=no --gtest_filter='Checkpoint.CudaResumed*'
    timeout 40 "$fl/bin/test_conservation" --gtest_color=no --gtest_filter='Conservation.Cuda*'
  ) 2>&1 | grep -E '^\[ *(OK|FAILED|SKIPPED|PASSED) |Failure|Expected|actual|^[a-z_0-9]+ (double|float) [23]D|NVIDIA' |
    tee "$out/tests.log"
  t0=$SECONDS
  LD_LIBRARY_PATH=$fl/lib timeout "${BASIN_LIMIT:-120}" "$fl/bin/flume" run scenes/waseda/waseda_2d.json \
    --backend cuda --set solver.dx=0.01 --out "$fl/w2d_dx001" -q --set \
    'instruments.sections=[{"name":"S060","x_m":0.6,"rate_hz":200},{"name":"S435","x_m":4.35,"rate_hz":200},{"name":"S469","x_m":4.69,"rate_hz":200}]'
  echo "waseda_2d dx 0.01 cuda: rc $?, $((SECONDS - t0)) s wall" | tee -a "$out/tests.log"
  cp "$fl/w2d_dx001/result.h5" "$out/w2d_dx001.h5" 2>/dev/null
  SF_END=${SF_END:-10} "$0" validation-runs 2>&1 | tee -a "$out/tests.log"
  exit 0
fi
if [[ $mode == validation-runs ]]; then
  unpack_flume
  export LD_LIBRARY_PATH=$fl/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  set +e  # a run that fails or overruns is reported, and the next one runs
  for dx in ${SF_DX:-0.075 0.05 0.0375}; do
    t0=$SECONDS
    timeout "${SF_LIMIT:-240}" "$fl/bin/flume" run scenes/validation/soares_frazao_2007_3d.json --backend cuda \
      --set solver.dx="$dx" --set solver.end_time="${SF_END:-10}" --out "$fl/sf_$dx" -q
    echo "soares_frazao dx $dx: rc $?, $((SECONDS - t0)) s wall"
    cp "$fl/sf_$dx/result.h5" "$out/sf_dx$dx.h5" 2>/dev/null || true
    cp "$fl/sf_$dx/run.json" "$out/sf_dx$dx.run.json" 2>/dev/null || true
  done
  exit 0
fi
if [[ $mode == flume-runs ]]; then
  unpack_flume
  export LD_LIBRARY_PATH=$fl/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  set +e  # a run that fails or overruns is reported, and the next one runs
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader || true
  echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $(git describe --always --dirty 2>/dev/null || echo unknown)"
  one() {  # one NAME TIMEOUT flume-run-arguments...
    local name=$1 limit=$2
    shift 2
    local t0=$SECONDS
    timeout "$limit" "$fl/bin/flume" run "$@" --out "$fl/$name" -q >"$fl/$name.log" 2>&1
    local rc=$?
    cp "$fl/$name/run.json" "$out/$name.run.json" 2>/dev/null || true
    python3 - "$fl/$name/run.json" "$name" "$rc" "$((SECONDS - t0))" <<'PY' || echo "$name: rc $rc, no run.json"
import json, sys
path, name, rc, wall = sys.argv[1:5]
d = json.load(open(path))
m, c = d["metrics"], d["cost"]
keys = sorted(k for k in m if k.endswith((".longitudinal_max_m", ".lateral_rest_m")) or k in ("WG1.peak_m", "WG2.peak_m", "WG3.peak_m"))
print(f"{name}: rc {rc}, status {d['status']}, {wall} s wall, {c['steps']} steps, {c['particles']} particles, "
      f"{c['particle_steps_per_s']:.3g} particle-steps/s; " + ", ".join(f"{k} {m[k]:.4f}" for k in keys))
PY
  }
  strip=scenes/waseda/waseda_strip.json
  one strip_dx050_double_cuda 30 "$strip" --backend cuda --set solver.precision=double
  one strip_dx050_double_cpu 45 "$strip" --backend cpu --set solver.precision=double
  one strip_dx050_cuda 30 "$strip" --backend cuda
  one strip_dx050_cuda_again 30 "$strip" --backend cuda  # atomics' order: how far two GPU runs differ
  one strip_dx050_cpu 45 "$strip" --backend cpu
  one strip_dx025_cuda 60 "$strip" --backend cuda --set solver.dx=0.025
  one basin_dx040_cuda 70 scenes/waseda/waseda_3d.json --backend cuda
  exit 0
fi

if [[ -d .gpu/lib ]]; then
  export LD_LIBRARY_PATH=$root/.gpu/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
fi
flume=${FLUME:-}
test_cuda=${TEST_CUDA:-$root/.gpu/bin/test_cuda}
steps=${STEPS:-200}
[[ -x $test_cuda ]] || { echo "run_gpu_bench.sh: no test_cuda at $test_cuda (bundle first, or set TEST_CUDA)" >&2; exit 2; }
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader || true
echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $(git describe --always --dirty 2>/dev/null || echo unknown)"

device=$(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1 || true)
device=${device:-unknown device}
if [[ $mode == all ]]; then
  # The tests read the scenes from this checkout and call this flume. The emulated backend's tests (CudaEmulation.*)
  # run on every build machine; here only those that need the device.
  # Cuda.RunWritesResult runs `flume run --backend cuda`: only where FLUME names a flume to run.
  filter='Cuda.*:CudaCli.*'
  [[ -n $flume ]] || filter+=':-Cuda.RunWritesResult'
  FLUME_EXE=${flume:-/nonexistent} FLUME_SOURCE_DIR=$root "$test_cuda" --gtest_color=no \
    --gtest_filter="$filter" | grep -E '^\[|^(cpu|other|column|martin|free|half|tank|box|waseda)|Failure|Expected|actual' || tests_failed=1
fi

# The benchmark scene: bench/scenes/dam_break_3d_1m.json when present (the CPU benchmark's), else the same
# dam break written here: a 1.0 x 0.5 x 0.5 m block at dx = 12.5 mm, 8 particles per cell = 1,024,000 particles.
scene=$root/bench/scenes/dam_break_3d_1m.json
if [[ ! -f $scene ]]; then
  scene=$(mktemp --suffix=.json)
  cat >"$scene" <<'EOF'
{
  "name": "dam_break_3d_1m",
  "dimension": 3,
  "domain": {"lo": [-0.05, -0.05, -0.05], "hi": [3.25, 0.55, 1.0], "walls": "slip"},
  "solver": {"dx": 0.0125, "ppc": 8, "cfl": 0.4, "precision": "float", "end_time": 2.0},
  "fluid": {"density": 1000, "bulk_modulus": 2.0e6, "gamma": 7.0, "viscosity": 1.0e-3, "jbar_psi": 0.9},
  "water": [{"lo": [0.0, 0.0, 0.0], "hi": [1.0, 0.5, 0.5]}],
  "boundaries": [
    {"name": "back_wall", "type": "half_space", "point": [0.0, 0.0, 0.0], "normal": [1.0, 0.0, 0.0], "condition": "slip"},
    {"name": "end_wall", "type": "half_space", "point": [3.2, 0.0, 0.0], "normal": [-1.0, 0.0, 0.0], "condition": "slip"},
    {"name": "side_left", "type": "half_space", "point": [0.0, 0.0, 0.0], "normal": [0.0, 1.0, 0.0], "condition": "slip"},
    {"name": "side_right", "type": "half_space", "point": [0.0, 0.5, 0.0], "normal": [0.0, -1.0, 0.0], "condition": "slip"},
    {"name": "floor", "type": "half_space", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "condition": "slip"}
  ],
  "instruments": {
    "gauges": [{"name": "mid", "position": [1.6, 0.25], "rate_hz": 100}],
    "diagnostics_rate_hz": 100,
    "snapshot_rate_hz": 0
  }
}
EOF
fi

# The large case: the same dam break at a finer dx (the count grows as dx^-3: 21.9 million at 4.5 mm).
large_dx=${LARGE_DX:-0.0045}
large=$(mktemp --suffix=.json)
sed -e "s/\"dx\": 0.0125/\"dx\": $large_dx/" -e 's/"name": "dam_break_3d_1m"/"name": "dam_break_3d_large"/' "$scene" >"$large"
large_steps=${LARGE_STEPS:-$((steps / 4 > 10 ? steps / 4 : 10))}

echo
echo "Device: $device. Scene: bench/scenes/dam_break_3d_1m.json (and dx $large_dx for the large case)."
echo
echo "| device | case | precision | particles | steps | ms/step | particle-steps/s | grid MB | active blocks |"
echo "|---|---|---|---|---|---|---|---|---|"
bench() {  # bench CASE SCENE STEPS
  FLUME_GPU_BENCH_SCENE=$2 FLUME_GPU_BENCH_STEPS=$3 FLUME_SOURCE_DIR=$root \
    "$test_cuda" --gtest_color=no --gtest_filter=CudaBench.* | grep -E '^\| (float|double)' |
    sed -e "s/^| /| $device | $1 | /" || echo "| $device | $1 | (failed or skipped) | | | | | | |"
}
bench "dam break 1M" "$scene" "$steps"
bench "dam break large" "$large" "$large_steps"

# The product's own scene: the whole Waseda basin in 3D (reservoir, gate, quay, apron, gauges), at its shipped dx
# and at half of it, to see what a real scene's boxes, forcing and instruments cost against the bare dam break.
waseda=$root/scenes/waseda/waseda_3d.json
waseda_fine=$(mktemp --suffix=.json)
sed -e 's/"dx": 0.04/"dx": 0.02/' "$waseda" >"$waseda_fine"
bench "waseda_3d dx 0.04" "$waseda" "$steps"
bench "waseda_3d dx 0.02" "$waseda_fine" "$large_steps"

# Debris on the GPU: the strip with its three containers (the rigid bodies on the host, the exchange's nodes and
# pushed-out particles copied each step), at its shipped dx and at half of it.
strip=$root/scenes/waseda/waseda_strip.json
strip_fine=$(mktemp --suffix=.json)
sed -e 's/"dx": 0.05/"dx": 0.025/' "$strip" >"$strip_fine"
bench "waseda_strip 3 debris dx 0.05" "$strip" "$steps"
bench "waseda_strip 3 debris dx 0.025" "$strip_fine" "$large_steps"

if [[ -n $flume ]]; then
  echo
  echo "flume bench --backend cuda:"
  for p in float double; do
    "$flume" bench "$scene" --steps "$steps" --backend cuda --set solver.precision="$p" |
      grep -E '"(precision|particles|steps|wall_s|particle_steps_per_s|grid_mb)"' | tr -d '\n '
    echo
  done
fi
[[ $tests_failed == 0 ]] || { echo "run_gpu_bench.sh: some CUDA tests failed (above)" >&2; exit 1; }
