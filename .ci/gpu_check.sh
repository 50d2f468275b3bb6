#!/usr/bin/env bash
# `make gpu-check`: every GPU figure of docs/performance.md in one command, on a machine with an NVIDIA GPU.
#
# Each benchmark runs under its own time limit (the whole script at most about 7 minutes) and its JSON line is
# collected into $GPU_CHECK_OUT/gpu_check.json, one object keyed by the figure's name, written as each
# one ends (so a script stopped early keeps what it measured). Taichi's kernel cache is kept in
# $TI_OFFLINE_CACHE_FILE_PATH (default: .ticache/ in the checkout, which git ignores), so a second run
# on a machine still warm compiles nothing; the cold compile is timed in an empty cache of its own.
#
#   make gpu-check                       # with the project's venv
#   PY=python3 bash .ci/gpu_check.sh     # with another interpreter that has taichi (PYTHONPATH=. is set)
set -u
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
OUT_DIR=${GPU_CHECK_OUT:-out}
mkdir -p "$OUT_DIR"
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1
export TI_OFFLINE_CACHE_FILE_PATH=${TI_OFFLINE_CACHE_FILE_PATH:-$PWD/.ticache}
ONLY=${GPU_CHECK_ONLY:-.}  # a regular expression: run only the figures whose names match
GPU_ARCH=${GPU_ARCH:-cuda}  # cpu: a dry run of the script itself on a machine without a GPU
RESULT="$OUT_DIR/gpu_check.json"
echo "{}" >"$RESULT"

# figure NAME LIMIT_S [ENV=VALUE ...] -- ARGS...: run `ti-golf ARGS --json` under LIMIT_S seconds and keep its
# JSON line as RESULT[NAME] (or its exit status and last error line when it printed none). Where nvidia-smi
# answers, the card's memory in use is sampled every 0.2 s meanwhile: gpu_memory_before_mib (the first
# sample, before the process starts) and gpu_memory_peak_mib (the process's CUDA context, Taichi's memory
# pool and the arrays together: an upper bound on what the arrays take).
figure() {
  local name=$1 limit=$2
  shift 2
  [[ $name =~ $ONLY ]] || return 0
  local envs=()
  while [ "$1" != "--" ]; do envs+=("$1"); shift; done
  shift
  local log="$OUT_DIR/$name.log" start end
  echo "== $name (limit ${limit} s): ti-golf $*" >&2
  : >"$log.mem"
  local sampler=""
  if command -v nvidia-smi >/dev/null 2>&1; then
    nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits -lms 200 >"$log.mem" 2>/dev/null &
    sampler=$!
    sleep 0.3
  fi
  start=$(date +%s.%N)
  env "${envs[@]}" timeout -s INT -k 20 "$limit" "$PY" -m ti_golf "$@" --json >"$log.out" 2>"$log"
  local rc=$?
  end=$(date +%s.%N)
  [ -n "$sampler" ] && kill "$sampler" 2>/dev/null && wait "$sampler" 2>/dev/null
  "$PY" - "$RESULT" "$name" "$log.out" "$log" "$rc" "$start" "$end" "$*" "$log.mem" <<'PY'
import json, os, sys
result, name, out, err, rc, start, end, args, mem = sys.argv[1:]
printed = open(out).read().strip().splitlines()
lines = [l for l in printed if l.startswith("{")]
if lines:
    entry = json.loads(lines[-1])
elif int(rc) == 0:
    entry = {"printed": (printed or ["(nothing)"])[-1]}
else:
    entry = {"error": (open(err).read().strip().splitlines() or ["(nothing)"])[-1]}
command = "ti-golf " + args + " --json"
entry.update(exit_status=int(rc), process_wall_s=round(float(end) - float(start), 2), command=command)
used = [int(s) for s in open(mem).read().split() if s.isdigit()]
if used:
    entry.update(gpu_memory_before_mib=used[0], gpu_memory_peak_mib=max(used))
data = json.load(open(result))
data[name] = entry
tmp = result + ".tmp"
json.dump(data, open(tmp, "w"), indent=1)
os.replace(tmp, result)
print(f"   exit {rc}, {float(end) - float(start):.1f} s", file=sys.stderr)
PY
}

nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader >"$OUT_DIR/gpu.txt" 2>&1 || true
cold=$(mktemp -d)
# The pour's kernels compiled from an empty cache (a pour of a few thousand balls: compile time is reported apart).
figure cuda_cold_compile 50 TI_OFFLINE_CACHE_FILE_PATH="$cold" -- bench pit --n 8192 --t 0.05 --arch "$GPU_ARCH"
# Its kernels are the pour's: keep them, so that the pours below do not compile them again.
mkdir -p "$TI_OFFLINE_CACHE_FILE_PATH" && cp -r "$cold"/. "$TI_OFFLINE_CACHE_FILE_PATH"/
rm -rf "$cold"
# The build's reductions over 100,000 balls, both ways their threads can meet (bench reductions).
figure cuda_reductions 30 -- bench reductions --arch "$GPU_ARCH"
figure cuda_pit_100k 100 -- bench pit --every 0.25 --arch "$GPU_ARCH"
figure cuda_pit_1m 60 -- bench pit --n 1000000 --every 0.25 --arch "$GPU_ARCH"
# Where a GPU step's time goes while the balls land: each kernel's seconds and launches against the wall.
figure cuda_pit_profile 40 -- bench pit --t 0.3 --profile --arch "$GPU_ARCH"
# How the CPU backend scales: the same stretch of the 100,000-ball pour (its first 0.4 s, the box falling
# and its first layers landing: 24 s on two cores of the CI class) on 16 threads and on 2; each run's
# loop_s says what a parallel loop costs the thread pool with that many threads.
figure cpu16_pit_100k 40 TI_CPU_MAX_NUM_THREADS=16 -- bench pit --t 0.4 --every 0.2 --arch cpu
figure cpu2_pit_100k 50 TI_CPU_MAX_NUM_THREADS=2 -- bench pit --t 0.4 --every 0.2 --arch cpu
# The lab on CUDA: the 100,000-ball pour in its window (hidden), frame after frame for 20 s as fast as it
# goes (sim_s_per_wall_s: the aim is at least 0.1), its last picture kept in $OUT_DIR/lab_pit_cuda.png.
figure cuda_lab_pit 60 -- bench lab ball_pit --seconds 20 --arch "$GPU_ARCH" --screenshot "$OUT_DIR/lab_pit_cuda.png"
# The serial step against the parallel one at SERIAL_MAX_BALLS, on 16 threads (serial_speedup: on two cores
# the serial step is 3.6x faster at 2,000 balls; more threads favour the parallel step).
figure cpu16_serial_4096 20 TI_CPU_MAX_NUM_THREADS=16 -- bench collide --n 4096 --steps 100 --arch cpu
cat "$RESULT"
