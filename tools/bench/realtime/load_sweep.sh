#!/usr/bin/env bash
# A busy computer (issue 41): the real-time pipeline on a EuRoC folder (config/pipelines/euroc_realtime.yaml,
# through tools/bench/realtime/latency_cpu.sh) beside 0, 1, 2, 4 and 8 busy processes (a shell loop
# spinning a core each, nice 0, as another program would) and beside an I/O load (a writer of 64 MB
# files, fsync'ed, and a reader of them, nice 0), RUNS runs per level, and once in lockstep
# (config/pipelines/euroc.yaml) for the reference ATE and keyframes. One row per run: frames
# tracked / published, missed (of them shed), keyframes, ATE, latency p50 / p99 / max, CPU share per process.
#   tools/bench/realtime/load_sweep.sh DATASET OUT_DIR [RUNS] [DOMAIN] [LEVELS] [-- SUPERVISOR ARGS]
# LEVELS: a comma-separated list of busy-process counts and "io" (default 0,1,2,4,8,io), e.g.
#   tools/bench/realtime/load_sweep.sh ../shared/data/euroc_mh01_handheld /tmp/sweep 2 227
# The busy processes are this script's children, stopped (by their pids) after each level.
# The machine's own load adds to the levels': the load average is printed with every level.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
usage="usage: load_sweep.sh DATASET OUT_DIR [RUNS] [DOMAIN] [LEVELS] [-- SUPERVISOR ARGS]"
dataset=${1:?$usage}
out=${2:?$usage}
runs=${3:-1}
domain=${4:-217}
levels=${5:-0,1,2,4,8,io}
shift $(($# < 5 ? $# : 5))
[[ ${1:-} == -- ]] && shift
extra=("$@")
[[ -d $dataset ]] || { echo "load_sweep.sh: dataset '$dataset' is not a folder" >&2; exit 2; }
mkdir -p "$out"

busy_pids=()
stop_load() {
  local pid
  for pid in "${busy_pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${busy_pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  busy_pids=()
  rm -rf "$out/io_load"
}
trap stop_load EXIT

start_load() {
  local level=$1 i
  if [[ $level == io ]]; then
    mkdir -p "$out/io_load"
    # A writer of fsync'ed 64 MB files and a reader of them (cache dropped by rewriting): disk and page cache busy.
    (while :; do dd if=/dev/zero of="$out/io_load/a" bs=1M count=64 conv=fsync status=none; done) &
    busy_pids+=($!)
    (while :; do cat "$out/io_load/a" >/dev/null 2>&1 || sleep 0.1; done) &
    busy_pids+=($!)
  else
    for ((i = 0; i < level; ++i)); do
      (while :; do :; done) &
      busy_pids+=($!)
    done
  fi
}

# The lockstep reference: ATE and keyframes.
lock=$out/lockstep
rm -rf "$lock.txt"* "$out/logs_lockstep"
"$bin/heslam-supervisor" "$root/config/pipelines/euroc.yaml" --domain "$domain" --log-dir "$out/logs_lockstep" \
  --arg dataset="$dataset" --arg output="$lock.txt" >"$lock.supervisor.log" 2>&1 ||
  { echo "load_sweep.sh: the lockstep run failed; see $lock.supervisor.log" >&2; exit 1; }
lock_kf=$(grep -h -E 'processed [0-9]+ frames' "$out/logs_lockstep/frontend.log" | tail -n 1 |
  sed -E 's/.*, ([0-9]+) keyframes.*/\1/')
lock_ate=$("$bin/heslam-eval" ape --gt "$dataset/mav0/state_groundtruth_estimate0/data.csv" --est "$lock.txt" \
  2>/dev/null | grep -m1 -E '^ *rmse' |
  awk '{ s = $3 == "m" ? 1000 : $3 == "cm" ? 10 : $3 == "mm" ? 1 : -1; if (s > 0) printf "%.2f", $2 * s }')
echo "# lockstep (euroc.yaml): ATE ${lock_ate:-?} mm, ${lock_kf:-?} keyframes"

IFS=, read -r -a level_list <<<"$levels"
failures=0
for level in "${level_list[@]}"; do
  [[ $level == io || $level =~ ^[0-9]+$ ]] || { echo "load_sweep.sh: level '$level': a number or io" >&2; exit 2; }
  start_load "$level"
  sleep 1
  echo "## level $level ($( [[ $level == io ]] && echo 'I/O load' || echo "$level busy processes"))"
  LABEL=load_$level "$here/latency_cpu.sh" "$dataset" "$out/level_$level" "$runs" "$domain" -- "${extra[@]}" ||
    failures=$((failures + 1))
  stop_load
done
((failures == 0)) || { echo "load_sweep.sh: runs failed at $failures levels (rows above)" >&2; exit 1; }
