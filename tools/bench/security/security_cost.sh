#!/usr/bin/env bash
# What DDS Security costs (docs/security.md): runs config/pipelines/euroc.yaml (lockstep, the full
# system) on a EuRoC folder plain and secure (--arg security=DIR, made here with heslam-security),
# alternating, RUNS times each, and prints per run: the frontend's per-frame time (stage "total",
# median / p90), the run's wall time, the CPU time of the whole run (user + sys of the supervisor and
# every process it started) and whether the trajectory is bit-identical to the first plain run.
# Then the one-way transport latency of stereo pairs (heslam-bench-transport: heslam-replay -> a
# subscriber) plain and secure, both processes running as identity "bench".
#   tools/bench/security/security_cost.sh DATASET OUT_DIR [RUNS] [DOMAIN]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
dataset=${1:?usage: security_cost.sh DATASET OUT_DIR [RUNS] [DOMAIN]}
out=${2:?usage: security_cost.sh DATASET OUT_DIR [RUNS] [DOMAIN]}
runs=${3:-2}
domain=${4:-212}
mkdir -p "$out"

security=$out/security
if [[ ! -d $security/ca ]]; then
  # The transport bench is publisher (heslam-replay) and subscriber under one identity.
  "$bin/heslam-security" init "$security" \
    --identity "bench:camera/stereo,camera/calibration,system/status:camera/stereo,camera/calibration,system/status,lockstep/frame_done" \
    >/dev/null
fi

printf "%-7s %3s  %-22s %8s  %-16s %s\n" mode run "frontend total ms" "wall s" "cpu s (u+s)" "output"
reference=""
for run in $(seq 1 "$runs"); do
  for mode in plain secure; do
    label=${mode}_$run
    extra=()
    [[ $mode == secure ]] && extra=(--arg security="$security")
    start=$(date +%s.%N)
    /usr/bin/time -f "%U %S" -o "$out/$label.time" "$bin/heslam-supervisor" "$root/config/pipelines/euroc.yaml" \
      --domain "$domain" --log-dir "$out/logs_$label" --arg dataset="$dataset" --arg output="$out/$label.txt" \
      "${extra[@]}" >"$out/$label.supervisor.log" 2>&1 || echo "run $label failed: $(tail -1 "$out/$label.supervisor.log")"
    wall=$(echo "$(date +%s.%N) - $start" | bc)
    cpu=$(awk '{printf "%.1f", $1 + $2}' "$out/$label.time")
    frame_ms=$(grep -h "stage total" "$out/logs_$label/frontend.log" | sed -E 's/.*median +([0-9.]+) ms +p90 +([0-9.]+) ms.*/\1 \/ \2/')
    [[ -z $reference ]] && reference=$out/$label.txt
    same=$(cmp -s "$reference" "$out/$label.txt" && echo "bit-identical" || echo "DIFFERS")
    printf "%-7s %3s  %-22s %8.1f  %-16s %s\n" "$mode" "$run" "$frame_ms" "$wall" "$cpu" "$same"
  done
done

echo
echo "transport, EuRoC and KITTI-sized pairs at 20 Hz (heslam-bench-transport --frames 200):"
for mode in plain secure; do
  if [[ $mode == secure ]]; then
    HESLAM_SECURITY=$security/identities/bench "$bin/heslam-bench-transport" --frames 200 --domain "$domain" \
      --no-plain-c --ddsperf-seconds 0 >"$out/transport_$mode.log" 2>&1 || echo "transport $mode failed"
  else
    "$bin/heslam-bench-transport" --frames 200 --domain "$domain" --no-plain-c --ddsperf-seconds 0 \
      >"$out/transport_$mode.log" 2>&1 || echo "transport $mode failed"
  fi
  echo "--- $mode"
  cat "$out/transport_$mode.log"
done
