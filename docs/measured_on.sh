#!/usr/bin/env bash
# Prints the line that heads every re-measured table in docs/: the commit the solver was built from (as the binary
# reports it, `flume --version`), the date, the machine, the build and the threads. Sourced by the scripts beside the docs (docs/tradeoff/, docs/waseda/,
# docs/debris/), or run on its own:  docs/measured_on.sh FLUME [THREADS]
measured_on() {  # measured_on FLUME THREADS
  local flume=$1 threads=$2 root build cache native="?" type="?"
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
  build=$(cd "$(dirname "$(realpath "$flume")")/.." && pwd)
  cache=$build/CMakeCache.txt
  if [[ -f $cache ]]; then
    native=$(sed -n 's/^FLUME_NATIVE:BOOL=//p' "$cache")
    type=$(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$cache")
  fi
  local version commit kernels
  version=$("$flume" --version 2>/dev/null | head -1)  # flume 0.1.0 (ab61e6f, portable build, avx2 CPU kernels)
  commit=$(sed -n 's/.*(\([^,]*\),.*/\1/p' <<<"$version")
  kernels=$(sed -n 's/.*, \([a-z0-9]*\) CPU kernels).*/, \1 CPU kernels/p' <<<"$version")  # solver/cpu_kernels.h
  [[ -n $commit ]] || commit="$(git -C "$root" rev-parse --short HEAD) (the working tree's; the binary does not say)"
  printf 'Measured at commit %s, %s UTC; %s, %s cores (%s GiB), load average %s before the runs; build %s, %s%s; %s OpenMP thread(s) per run, one run at a time.\n' \
    "$commit" "$(date -u '+%F %H:%M')" \
    "$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1)" "$(nproc --all)" "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)" \
    "$(cut -d' ' -f1-3 /proc/loadavg)" "$type" "$([[ $native == ON ]] && echo native || echo portable)" "$kernels" "$threads"
}

# Runs SCENE into OUT unless OUT already holds a finished run (a killed script resumes where it stopped), then
# prints the header of its first start and the run's cost. Arguments after THREADS go to `flume run` (--set ...).
run_scene_once() {  # run_scene_once FLUME SCENE OUT THREADS [RUN ARGUMENTS...]
  local flume=$1 scene=$2 out=$3 threads=$4
  shift 4
  mkdir -p "$out"
  [[ -f $out/header.txt ]] || measured_on "$flume" "$threads" >"$out/header.txt"
  if ! grep -qs '"status": "ok"' "$out/run.json"; then
    OMP_WAIT_POLICY=PASSIVE /usr/bin/time -o "$out.time" -f '%e s wall, %U s user, %S s system' \
      "$flume" run "$scene" --out "$out" --quiet --threads "$threads" "$@"
  fi
  cat "$out/header.txt"
  echo
  echo "cost: $(jq -c .cost "$out/run.json"); $(cat "$out.time" 2>/dev/null)"
  echo
}
if [[ ${BASH_SOURCE[0]} == "$0" ]]; then measured_on "${1:-build/bin/flume}" "${2:-${OMP_NUM_THREADS:-?}}"; fi
