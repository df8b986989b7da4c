#!/usr/bin/env bash
# Latency and CPU share of the real-time pipeline (issue 41): runs config/pipelines/euroc_realtime.yaml
# (replay at the recording's rate, frontend, local mapper, loop closer, recorder) RUNS times over a
# EuRoC folder and prints one row per run:
#   tracked / published frames, missed (of them shed by the frontend because it was behind), keyframes,
#   ATE (mm, with ground truth), latency p50 / p99 / max (from a frame's publication by the replay to
#   its odometry sample: the frontend's `latency` stage), the frontend's per-frame CPU (stage `cpu`,
#   median), and the CPU share of each process (% of one core, from /proc/PID/stat over the replay's
#   lifetime: the frames' time, start-up of the others excluded).
#   tools/bench/realtime/latency_cpu.sh DATASET OUT_DIR [RUNS] [DOMAIN] [-- EXTRA SUPERVISOR ARGS]
# e.g. tools/bench/realtime/latency_cpu.sh ../shared/data/euroc_mh01_handheld /tmp/lat 3 227
# LABEL=NAME (environment): the rows' label prefix (tools/bench/realtime/load_sweep.sh names its levels);
# PIPELINE=NAME: another real-time pipeline of config/pipelines (default euroc_realtime).
# Not repeatable run to run (real time depends on the machine's load): the load is printed with the rows.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
usage="usage: latency_cpu.sh DATASET OUT_DIR [RUNS] [DOMAIN] [-- SUPERVISOR ARGS]"
dataset=${1:?$usage}
out=${2:?$usage}
runs=${3:-1}
domain=${4:-217}
shift $(($# < 4 ? $# : 4))
[[ ${1:-} == -- ]] && shift
extra=("$@")
label=${LABEL:-rt}
pipeline=${PIPELINE:-euroc_realtime}
[[ -d $dataset ]] || { echo "latency_cpu.sh: dataset '$dataset' is not a folder" >&2; exit 2; }
[[ $runs =~ ^[1-9][0-9]*$ ]] || { echo "latency_cpu.sh: RUNS '$runs': expected a positive integer" >&2; exit 2; }
mkdir -p "$out"
hz=$(getconf CLK_TCK)

# One number from a log line matching `pattern`, by a sed expression; "-" when absent.
field() {
  local file=$1 pattern=$2 expression=$3 value
  value=$(grep -h -E "$pattern" "$file" 2>/dev/null | tail -n 1 | sed -E "$expression" || true)
  [[ -n $value ]] && echo "$value" || echo "-"
}

ate_mm() {
  local trajectory=$1 gt=$dataset/mav0/state_groundtruth_estimate0/data.csv rmse
  [[ -f $gt && -s $trajectory ]] || { echo "-"; return; }
  rmse=$("$bin/heslam-eval" ape --gt "$gt" --est "$trajectory" 2>/dev/null |
    grep -m1 -E '^ *rmse' | awk '{ s = $3 == "m" ? 1000 : $3 == "cm" ? 10 : $3 == "mm" ? 1 : $3 == "um" ? 0.001 : -1
                                   if (s > 0) printf "%.2f", $2 * s }' || true)
  [[ -n $rmse ]] && echo "$rmse" || echo "-"
}

# CPU ticks (utime + stime) of each child of PID, one "name ticks" line each (name: the executable).
child_ticks() {
  local parent=$1 pid name
  for pid in $(pgrep -P "$parent" 2>/dev/null || true); do
    name=$(tr '\0' '\n' 2>/dev/null <"/proc/$pid/cmdline" | head -n 1) || continue
    [[ -n $name ]] || continue
    # Fields after the ")" of the comm: utime and stime are the 12th and 13th.
    awk -v name="${name##*/}" '{ sub(/^.*\) /, ""); print name, $12 + $13 }' "/proc/$pid/stat" 2>/dev/null || true
  done
}

# Samples the supervisor's children every 0.2 s while it runs; writes OUT (name cpu_s share_%) for the
# replay's lifetime: from its first sample to its last.
sample_cpu() {
  local supervisor=$1 result=$2 samples now
  samples=$result.samples
  : >"$samples"
  while kill -0 "$supervisor" 2>/dev/null; do
    now=$(date +%s.%N)
    child_ticks "$supervisor" | awk -v t="$now" '{ print t, $1, $2 }' >>"$samples"
    sleep 0.2
  done
  # Window: the first and last sample in which the replay was alive; every process's ticks at both.
  awk -v hz="$hz" '
    $2 == "heslam-replay" { if (first == "") first = $1; last = $1 }
    { t[NR] = $1; n[NR] = $2; v[NR] = $3 }
    END {
      if (first == "" || last == first) exit
      for (i = 1; i <= NR; ++i) {
        if (t[i] == first) start[n[i]] = v[i]
        if (t[i] == last) end[n[i]] = v[i]
      }
      for (name in end) if (name in start) printf "%s %.2f %.1f\n", name, (end[name] - start[name]) / hz,
                                                   100 * (end[name] - start[name]) / hz / (last - first)
    }' "$samples" | sort >"$result"
}

share_of() { awk -v n="$1" '$1 == n { print $3 }' "$2" | grep . || echo "-"; }

printf "# %s UTC, load average %s, commit %s, %s, dataset %s\n" "$(date -u '+%F %T')" \
  "$(cut -d' ' -f1-3 /proc/loadavg)" "$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo '?')" \
  "$pipeline.yaml" "$dataset"
header() {
  printf "%-12s %9s %6s %5s %4s %7s %7s %7s %7s %7s %6s %6s %6s %6s %6s\n" run tracked missed shed kf "ATE mm" \
    "lat p50" "lat p99" "lat max" "fe cpu" "fe %" "map %" "loop %" "rep %" "rec %"
}
header
failed=0
for run in $(seq 1 "$runs"); do
  name=${label}_$run
  logs=$out/logs_$name
  rm -rf "$logs" "$out/$name.txt"*
  "$bin/heslam-supervisor" "$root/config/pipelines/$pipeline.yaml" --domain "$domain" --log-dir "$logs" \
    --arg dataset="$dataset" --arg output="$out/$name.txt" "${extra[@]}" >"$out/$name.supervisor.log" 2>&1 &
  supervisor=$!
  sample_cpu "$supervisor" "$out/$name.cpu" &
  sampler=$!
  status=0
  wait "$supervisor" || status=$?
  wait "$sampler" || true
  if ((status != 0)); then
    # A loaded machine may fail a start-up (a component's first status later than the supervisor's
    # 10 s): the row says so, the other runs go on, and the script exits 1 at the end.
    printf "%-12s failed (exit %s): %s\n" "$name" "$status" \
      "$(grep -m1 -o 'pipeline failed: .*' "$out/$name.supervisor.log" | cut -c1-100 || true)"
    failed=$((failed + 1))
    continue
  fi
  fe=$logs/frontend.log
  tracked=$(field "$out/$name.supervisor.log" 'tracked [0-9]+/[0-9]+ frames' \
    's/.*tracked ([0-9]+\/[0-9]+) frames.*/\1/')
  missed=$(field "$fe" 'frames missed' 's/.* ([0-9]+) frames missed.*/\1/')
  [[ $missed == - ]] && missed=0
  shed=$(field "$fe" 'frames shed' 's/.* ([0-9]+) frames shed.*/\1/')
  [[ $shed == - ]] && shed=0
  keyframes=$(field "$fe" 'processed [0-9]+ frames' 's/.*, ([0-9]+) keyframes.*/\1/')
  lat50=$(field "$fe" '^.*latency \(frame published' 's/.* median ([0-9.]+) ms.*/\1/')
  lat99=$(field "$fe" '^.*latency \(frame published' 's/.* p99 ([0-9.]+) ms.*/\1/')
  latmax=$(field "$fe" '^.*latency \(frame published' 's/.* max ([0-9.]+) ms.*/\1/')
  cpu=$(field "$fe" 'stage cpu ' 's/.*median +([0-9.]+) ms.*/\1/')
  c=$out/$name.cpu
  printf "%-12s %9s %6s %5s %4s %7s %7s %7s %7s %7s %6s %6s %6s %6s %6s\n" "$name" "$tracked" "$missed" "$shed" \
    "$keyframes" "$(ate_mm "$out/$name.txt")" "$lat50" "$lat99" "$latmax" "$cpu" "$(share_of heslam-frontend "$c")" \
    "$(share_of heslam-local-mapper "$c")" "$(share_of heslam-loop-closer "$c")" "$(share_of heslam-replay "$c")" \
    "$(share_of heslam-recorder "$c")"
done
echo "# load average at the end $(cut -d' ' -f1-3 /proc/loadavg); lat: ms, fe cpu: the frontend's CPU per frame (ms," \
  "median), %: CPU share of one core over the replay's lifetime"
((failed == 0)) || { echo "latency_cpu.sh: $failed of $runs runs failed; see $out/" >&2; exit 1; }
