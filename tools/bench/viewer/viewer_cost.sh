#!/usr/bin/env bash
# What heslam-viewer costs: runs config/pipelines/euroc.yaml (lockstep) on a EuRoC folder
# without a viewer, with a headless viewer (snapshots every second) and with a displayed viewer on an
# Xvfb server (viz 3D window + highgui, software OpenGL), RUNS times each, and prints per run: the
# frontend's per-frame time (stage "total", median / p90), the run's wall time, the viewer's CPU time
# (user + sys, from /proc, up to the end of the run) and its share of one core over its lifetime, and whether the trajectory is
# bit-identical to the first run without the viewer.
#   tools/bench/viewer/viewer_cost.sh DATASET OUT_DIR [RUNS] [DOMAIN]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
dataset=${1:?usage: viewer_cost.sh DATASET OUT_DIR [RUNS] [DOMAIN]}
out=${2:?usage: viewer_cost.sh DATASET OUT_DIR [RUNS] [DOMAIN]}
runs=${3:-2}
domain=${4:-211}
display_number=$((400 + domain))
mkdir -p "$out"

xvfb_pid=""
cleanup() { [[ -n $xvfb_pid ]] && kill "$xvfb_pid" 2>/dev/null || true; }
trap cleanup EXIT

printf "%-8s %3s  %-22s %8s  %-26s %s\n" mode run "frontend total ms" "wall s" "viewer cpu" "output"
reference=""
for run in $(seq 1 "$runs"); do
  for mode in none headless display; do
    label=${mode}_$run
    viewer_pid=""
    if [[ $mode == display && -z $xvfb_pid ]]; then
      Xvfb ":$display_number" -screen 0 1920x1200x24 -nolisten tcp >/dev/null 2>&1 &
      xvfb_pid=$!
      sleep 1
    fi
    if [[ $mode != none ]]; then
      args=(--domain "$domain" --out "$out/${label}_pictures")
      [[ $mode == headless ]] && args+=(--headless --snapshot-every 1)
      if [[ $mode == display ]]; then
        DISPLAY=":$display_number" "$bin/heslam-viewer" "${args[@]}" >"$out/$label.viewer.log" 2>&1 &
      else
        env -u DISPLAY "$bin/heslam-viewer" "${args[@]}" >"$out/$label.viewer.log" 2>&1 &
      fi
      viewer_pid=$!
      sleep 1  # joined before the run starts: it sees every frame
    fi
    start=$(date +%s.%N)
    "$bin/heslam-supervisor" "$root/config/pipelines/euroc.yaml" --domain "$domain" \
      --log-dir "$out/logs_$label" --arg dataset="$dataset" --arg output="$out/$label.txt" >/dev/null 2>&1
    wall=$(echo "$(date +%s.%N) - $start" | bc)
    viewer_cpu="-"
    if [[ -n $viewer_pid ]]; then
      # CPU of the viewer until now (user + sys, clock ticks) over its lifetime so far, from /proc.
      read -r -a stat <"/proc/$viewer_pid/stat"
      ticks=$(getconf CLK_TCK)
      cpu_s=$(echo "(${stat[13]} + ${stat[14]}) / $ticks" | bc -l)
      uptime_s=$(cut -d' ' -f1 /proc/uptime)
      alive_s=$(echo "$uptime_s - ${stat[21]} / $ticks" | bc -l)
      viewer_cpu=$(printf "%.1f s (%.0f %% of %.0f s)" "$cpu_s" "$(echo "100 * $cpu_s / $alive_s" | bc -l)" "$alive_s")
      kill -TERM "$viewer_pid"
      wait "$viewer_pid" || true
    fi
    frame_ms=$(grep -h "stage total" "$out/logs_$label/frontend.log" | sed -E 's/.*median +([0-9.]+) ms +p90 +([0-9.]+) ms.*/\1 \/ \2/')
    [[ -z $reference ]] && reference=$out/$label.txt
    same=$(cmp -s "$reference" "$out/$label.txt" && echo "bit-identical" || echo "DIFFERS")
    printf "%-8s %3s  %-22s %8.1f  %-26s %s\n" "$mode" "$run" "$frame_ms" "$wall" "$viewer_cpu" "$same"
  done
done
