#!/usr/bin/env bash
# A long run of the whole system (replay + frontend + local mapper + loop closer + recorder, under the
# supervisor) over a heslam-synth sequence that keeps revisiting the same places (the room_laps preset:
# laps of the room for 30 min), recording how every process grows with time:
#
#   heslam-synth --preset room_laps --out DATA                       # 36000 frames, about 14 GB
#   tools/bench/long_run.sh DATA OUT_DIR                             # real time (30 min)
#   tools/bench/long_run.sh DATA OUT_DIR --lockstep --frames 1440    # lockstep, the first 4 laps
#
# options: --lockstep (config/pipelines/synth.yaml; default: real time, euroc_realtime.yaml with the
# synth camera settings), --frames N (replay only the first N frames), --domain D (DDS domain, 226),
# --lap-frames N (frames per lap for the per-lap table; default: the room_laps lap, 345 at 20 Hz: 13.8 m at 0.8 m/s).
#
# Every component's status (system/status, once a second; read by heslam-spy) becomes a row of
# OUT_DIR/status.csv: elapsed wall time, component, its RSS, and, from the frontend, frames tracked,
# keyframes it made and its per-frame time (stage total, p50 / p90 over its last 1000 frames); from the
# local mapper, the map's keyframes and points (counters map_*_added - map_*_removed), its time per
# keyframe (stage mapping_total, p50) and its map save (stage map_save, p50), with the size of the map
# file it keeps (STEM.map and its journal STEM.map.journal, saved after every keyframe). Then:
#   OUT_DIR/laps.csv   per lap (at the frontend's frame count k * lap_frames; in real time the frames it
#                      missed are not counted, so there a lap row comes a little late): map keyframes, points,
#                      map file size, map save p50, RSS of every process
#   OUT_DIR/long_run.svg  the same against elapsed time (tools/bench/long_run_plot.sh)
# and a growth line per further lap (lap k against lap k-1, from lap 2 on; the bounds of issue 41:
# keyframes < 10 %, RSS of every process < 10 %). Exit 1 when the run fails or records nothing.
# Real time depends on the machine's load: report `uptime` with the figures.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
usage="usage: long_run.sh DATASET OUT_DIR [--lockstep] [--frames N] [--domain D] [--lap-frames N]"
dataset=${1:?$usage}
out=${2:?$usage}
shift 2
lockstep=0
frames=0
domain=226
lap_frames=345
while [[ $# -gt 0 ]]; do
  case $1 in
    --lockstep) lockstep=1; shift ;;
    --frames) frames=${2:?$usage}; shift 2 ;;
    --domain) domain=${2:?$usage}; shift 2 ;;
    --lap-frames) lap_frames=${2:?$usage}; shift 2 ;;
    *) echo "long_run.sh: unknown argument '$1' ($usage)" >&2; exit 2 ;;
  esac
done
for value in "$frames" "$domain" "$lap_frames"; do
  [[ $value =~ ^[0-9]+$ ]] || { echo "long_run.sh: '$value' is not a non-negative integer" >&2; exit 2; }
done
[[ $lap_frames -gt 0 ]] || { echo "long_run.sh: --lap-frames must be positive" >&2; exit 2; }
[[ -d $dataset/mav0/cam0 ]] ||
  { echo "long_run.sh: dataset '$dataset' is not a EuRoC-layout folder (mav0/cam0)" >&2; exit 2; }
mkdir -p "$out"
out=$(cd "$out" && pwd)
rate_hz=$(awk '/^rate_hz:/ { print $2 }' "$dataset/mav0/cam0/sensor.yaml")
[[ -n $rate_hz ]] || { echo "long_run.sh: $dataset/mav0/cam0/sensor.yaml: no rate_hz" >&2; exit 2; }

duration=()
if [[ $frames -gt 0 ]]; then
  duration=(--arg duration_s="$(awk -v n="$frames" -v r="$rate_hz" 'BEGIN { printf "%.3f", (n - 0.5) / r }')")
fi
if [[ $lockstep == 1 ]]; then
  pipeline=(config/pipelines/synth.yaml)
else
  pipeline=(config/pipelines/euroc_realtime.yaml --arg settings="$root/config/camera/synth.yaml")
fi
trajectory=$out/trajectory.txt
map_file=$out/trajectory.map
rm -rf "$out/logs" "$trajectory" "$out"/trajectory.* "$out/status.csv" "$out/laps.csv" "$out/long_run.svg"

# The status stream as CSV rows; the spy's own status is left out.
parse_status() {
  awk -v start="$(date +%s.%N)" -v map_file="$map_file" -v OFS=, '
      function flush(   bytes, line, cmd) {
        if (name == "" || name == "long_run_spy") return
        bytes = ""
        if (name == "local_mapper") {
          # the snapshot and the journal appended since it (docs/local_mapper.md, Persistence)
          cmd = "stat -c %s " map_file " " map_file ".journal 2>/dev/null"
          while ((cmd | getline line) > 0) bytes += line
          close(cmd)
        }
        print stamp / 1e9 - start, name, pid, rss, c["frames"], c["keyframes"],
              (name == "local_mapper" ? c["map_keyframes_added"] - c["map_keyframes_removed"] : ""),
              (name == "local_mapper" ? c["map_points_added"] - c["map_points_removed"] : ""),
              p50["total"], p90["total"], p50["mapping_total"], p50["map_save"], bytes
        fflush()
      }
      BEGIN { print "elapsed_s", "component", "pid", "rss_mib", "frames", "keyframes_made", "map_keyframes",
                    "map_points", "frame_p50_ms", "frame_p90_ms", "mapper_kf_p50_ms", "map_save_p50_ms",
                    "map_file_bytes" }
      /^---/ { flush(); name = ""; delete c; delete p50; delete p90; next }
      /^name: / { name = $2 }
      /^pid: / { pid = $2 }
      /^stamp_ns: / { stamp = $2 }
      /^rss_mib: / { rss = $2 }
      /^  - [a-z_]+: [0-9]+$/ { key = $2; sub(/:$/, "", key); c[key] = $3 }
      /^  - [a-z_]+: \{count/ {
        key = $2; sub(/:$/, "", key)
        for (i = 3; i <= NF; ++i) {
          if ($i == "p50_ms:") { v = $(i + 1); sub(/,$/, "", v); p50[key] = v }
          if ($i == "p90_ms:") { v = $(i + 1); sub(/,$/, "", v); p90[key] = v }
        }
      }
      END { flush() }' >"$out/status.csv"
}
# The spy's own pid, so that it is the one stopped (it holds whatever the caller holds, e.g. a domain lock).
"$bin/heslam-spy" echo system/status --domain "$domain" --name long_run_spy --log-level warn > >(parse_status) &
collector=$!
trap 'kill "$collector" 2>/dev/null || true' EXIT

mode=$( [[ $lockstep == 1 ]] && echo lockstep || echo "real time")
echo "# $(date -u '+%F %T') UTC, load average $(cut -d' ' -f1-3 /proc/loadavg), $mode"
echo "# dataset $dataset, frames $frames (0: all)"
start=$(date +%s.%N)
status=0
(cd "$root" && "$bin/heslam-supervisor" "${pipeline[@]}" --domain "$domain" --log-dir "$out/logs" \
  --arg dataset="$dataset" --arg output="$trajectory" "${duration[@]}" >"$out/supervisor.log" 2>&1) || status=$?
sleep 2  # the last status samples
kill "$collector" 2>/dev/null || true
wait "$collector" 2>/dev/null || true
sleep 1  # the parser writes its last rows
trap - EXIT
wall=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
echo "# wall ${wall} s, load average at the end $(cut -d' ' -f1-3 /proc/loadavg)"
if [[ $status != 0 ]]; then
  echo "long_run.sh: the run failed (exit $status); see $out/supervisor.log and $out/logs/" >&2
  exit 1
fi
recorded=$( [[ -f $trajectory ]] && grep -cv '^#' "$trajectory" || echo 0)
[[ $recorded -gt 0 ]] || { echo "long_run.sh: no pose recorded in $trajectory" >&2; exit 1; }
[[ $(wc -l <"$out/status.csv") -gt 1 ]] || { echo "long_run.sh: no status sample in $out/status.csv" >&2; exit 1; }
grep -h -E 'saved the map|map file' "$out/logs/local_mapper.log" | tail -n 2 || true

# Per lap: the state at the first frontend sample with frames >= k * lap_frames (the last sample for
# the last, partial lap), each process's RSS from its sample nearest before that time.
awk -F, -v OFS=, -v lap="$lap_frames" -v recorded="$recorded" '
  NR == 1 { next }
  { t[NR] = $1; comp[NR] = $2; n = NR; if (!($2 in seen)) { seen[$2] = 1; order[++ncomp] = $2 } }
  $2 == "frontend" && $5 != "" { fe[++nfe] = NR }
  END {
    printf "lap,frames,elapsed_s,map_keyframes,map_points,map_file_bytes,map_save_p50_ms,mapper_kf_p50_ms,frame_p50_ms"
    for (k = 1; k <= ncomp; ++k) printf ",rss_mib_%s", order[k]
    printf "\n"
    laps = int(recorded / lap); if (recorded % lap > lap / 2) ++laps
    j = 1
    for (l = 1; l <= laps; ++l) {
      while (j < nfe && fields(fe[j], 5) < l * lap) ++j
      row = fe[j]
      delete last
      for (i = 2; i <= row; ++i) last[comp[i]] = i
      # the mapper sample at or before this time
      m = ("local_mapper" in last) ? last["local_mapper"] : 0
      printf "%d,%s,%.1f,%s,%s,%s,%s,%s,%s", l, fields(row, 5), t[row], m ? fields(m, 7) : "", m ? fields(m, 8) : "",
        m ? fields(m, 13) : "", m ? fields(m, 12) : "", m ? fields(m, 11) : "", fields(row, 9)
      for (k = 1; k <= ncomp; ++k) printf ",%s", (order[k] in last) ? fields(last[order[k]], 4) : ""
      printf "\n"
    }
  }
  function fields(r, f,   a) { split(line[r], a, ","); return a[f] }
  { line[NR] = $0 }' "$out/status.csv" >"$out/laps.csv"
column -t -s, "$out/laps.csv"

# Growth per further lap: keyframes and every process's RSS, lap k against lap k-1 (from lap 2 on).
awk -F, '
  NR == 1 { for (i = 1; i <= NF; ++i) head[i] = $i; nf = NF; next }
  { for (i = 1; i <= nf; ++i) v[NR - 1, i] = $i; laps = NR - 1 }
  END {
    for (l = 2; l <= laps; ++l) {
      printf "lap %d vs %d:", l, l - 1
      for (i = 4; i <= nf; ++i) {
        if (i != 4 && i != 5 && i != 6 && head[i] !~ /^rss_mib_/) continue
        a = v[l - 1, i]; b = v[l, i]
        if (a > 0) printf " %s %+.1f%%", head[i], 100 * (b - a) / a
      }
      printf "\n"
    }
  }' "$out/laps.csv" | tee "$out/growth.txt"
"$root/tools/bench/long_run_plot.sh" "$out/status.csv" >"$out/long_run.svg"
echo "# $out/status.csv, $out/laps.csv, $out/long_run.svg"
