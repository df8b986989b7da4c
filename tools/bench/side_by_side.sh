#!/usr/bin/env bash
# heslam and ORB-SLAM3 timed side by side: runs ORB-SLAM3's stereo example (stereo_euroc, paced like the
# camera) and heslam's real-time pipeline (config/pipelines/euroc_realtime.yaml, every process running)
# alternately on the same EuRoC folder, ROUNDS times, and prints both per-frame tracking times in one
# table, so the speed lead is measured in one window on one machine, never across days.
#   tools/bench/side_by_side.sh --orbslam3 DIR [--inertial] [--settings FILE] [--rounds N] [--domain D] DATASET OUT_DIR
# DIR is an ORB-SLAM3 checkout the user has built (Examples/Stereo/stereo_euroc, Vocabulary/ORBvoc.txt)
# with REGISTER_TIMES defined (ORB-SLAM3's README, "Running time analysis"): only then does it write its
# per-frame times (TrackingTimeStats.txt, column Total[ms]). --settings defaults to its
# Examples/Stereo/EuRoC.yaml. Figures: ORB-SLAM3's Total per frame (its TrackStereo call, image reading
# excluded) against heslam's frontend stage "total" per frame (image decoding is the replay's), medians
# and p90; frames with a pose; ATE (mm) of both against the ground truth when the folder has one.
# Real time depends on the machine's load: the table's first line records it.
# --inertial: stereo-inertial on both sides instead (issue 34; docs/imu.md, "Running ORB-SLAM3 beside
# heslam"): ORB-SLAM3's Examples/Stereo-Inertial/stereo_inertial_euroc with --settings defaulting to its
# Examples/Stereo-Inertial/EuRoC.yaml, beside config/pipelines/euroc_inertial_realtime.yaml; the folder
# needs mav0/imu0/data.csv (both read it). ORB-SLAM3's inertial trajectory is of the IMU (body) in its
# gravity-aligned world, so its ATE is taken against the ground truth's body poses directly.
# Both read the same frame-stamps file, which this script writes (OUT_DIR/times.txt, ORB-SLAM3's
# EuRoC_TimeStamps/MH01.txt format: one stamp in ns per line).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
usage="usage: side_by_side.sh --orbslam3 DIR [--inertial] [--settings FILE] [--rounds N] [--domain D] DATASET OUT_DIR"
fail() { echo "side_by_side.sh: $*" >&2; exit 2; }

orbslam3="" settings="" rounds=2 domain=217 inertial=0 positional=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --orbslam3) orbslam3=${2:?$usage}; shift 2 ;;
    --settings) settings=${2:?$usage}; shift 2 ;;
    --inertial) inertial=1; shift ;;
    --rounds) rounds=${2:?$usage}; shift 2 ;;
    --domain) domain=${2:?$usage}; shift 2 ;;
    --help | -h) echo "$usage"; exit 0 ;;
    -*) fail "unknown option '$1'; $usage" ;;
    *) positional+=("$1"); shift ;;
  esac
done
[[ ${#positional[@]} -eq 2 ]] || fail "$usage"
dataset=$(cd "${positional[0]}" 2>/dev/null && pwd) || fail "dataset '${positional[0]}' is not a folder"
out=${positional[1]}
[[ -n $orbslam3 ]] || fail "ORB-SLAM3 is missing: --orbslam3 DIR is required (an ORB-SLAM3 checkout built with" \
  "its build.sh and REGISTER_TIMES; heslam does not ship or build it: docs/imu.md, Running ORB-SLAM3 beside heslam)"
[[ -d $orbslam3 ]] || fail "ORB-SLAM3 is missing: --orbslam3 '$orbslam3' is not a folder"
orbslam3=$(cd "$orbslam3" && pwd)
if [[ $inertial == 1 ]]; then
  example=$orbslam3/Examples/Stereo-Inertial/stereo_inertial_euroc
  settings=${settings:-$orbslam3/Examples/Stereo-Inertial/EuRoC.yaml}
  heslam_kind=euroc_inertial
else
  example=$orbslam3/Examples/Stereo/stereo_euroc
  settings=${settings:-$orbslam3/Examples/Stereo/EuRoC.yaml}
  heslam_kind=euroc
fi
vocabulary=$orbslam3/Vocabulary/ORBvoc.txt
[[ -x $example ]] ||
  fail "ORB-SLAM3 is missing: no $(basename "$example") at $example (build ORB-SLAM3 first: its build.sh)"
[[ -f $vocabulary ]] || fail "no ORB-SLAM3 vocabulary at $vocabulary (its build.sh unpacks ORBvoc.txt.tar.gz)"
[[ -f $settings ]] || fail "--settings: no file $settings"
[[ $rounds =~ ^[1-9][0-9]*$ ]] || fail "--rounds '$rounds': expected a positive integer"
[[ $domain =~ ^[0-9]+$ ]] || fail "--domain '$domain': expected a DDS domain id"
frames_csv=$dataset/mav0/cam0/data.csv
[[ -f $frames_csv ]] || fail "$frames_csv: missing (expected an EuRoC folder with mav0/)"
if [[ $inertial == 1 && ! -f $dataset/mav0/imu0/data.csv ]]; then
  fail "$dataset/mav0/imu0/data.csv: missing (--inertial needs the IMU: EuRoC's imu0/)"
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)

# ORB-SLAM3 reads a file of frame stamps (ns), one per line: EuRoC's cam0/data.csv without its header.
times=$out/times.txt
awk -F, '!/^#/ && NF >= 2 { sub(/\r$/, "", $1); print $1 }' "$frames_csv" >"$times"
[[ -s $times ]] || fail "$frames_csv: no frames"

# median and p90 of a column of numbers on stdin ("- -" when empty).
median_p90() {
  sort -g | awk '{ v[NR] = $1 } END {
    if (NR == 0) { print "- -"; exit }
    m = NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2
    q = v[int(0.9 * (NR - 1)) + 1]
    printf "%.2f %.2f\n", m, q }'
}

# ATE rmse in mm of ORB-SLAM3's TUM trajectory, or "-" without ground truth: left-camera poses (stereo,
# through cam0's T_BS) or, --inertial, IMU (body) poses as the ground truth's.
ate_orbslam3_mm() {
  local trajectory=$1 gt=$dataset/mav0/state_groundtruth_estimate0/data.csv extrinsic=()
  [[ -f $gt && -s $trajectory ]] || { echo "-"; return; }
  [[ $inertial == 1 ]] || extrinsic=(--extrinsic "$dataset/mav0/cam0/sensor.yaml")
  "$bin/heslam-eval" ape --gt "$gt" "${extrinsic[@]}" --est "$trajectory" \
    --est-format tum --json - 2>/dev/null |
    sed -nE 's/.*"rmse": *([0-9.eE+-]+).*/\1/p' | head -n 1 | awk '{ printf "%.2f", $1 * 1000 }' || true
}

# One ORB-SLAM3 run in its own folder (it writes its statistics into the working directory).
# Prints: frames-with-pose median p90 ate.
run_orbslam3() {
  local dir=$out/orbslam3_$1 stats trajectory
  rm -rf "$dir" && mkdir -p "$dir"
  if ! (cd "$dir" && "$example" "$vocabulary" "$settings" "$dataset" "$times" trajectory >run.log 2>&1); then
    echo "side_by_side.sh: ORB-SLAM3 round $1 failed; see $dir/run.log" >&2
    exit 1
  fi
  stats=$dir/TrackingTimeStats.txt
  if [[ ! -s $stats ]]; then
    echo "side_by_side.sh: ORB-SLAM3 wrote no $stats: build it with REGISTER_TIMES defined" \
      "(its README, 'Running time analysis')" >&2
    exit 1
  fi
  # Versions differ in the name of the frame trajectory: trajectory_frames.txt or f_trajectory.txt.
  trajectory=$(ls "$dir"/trajectory_frames.txt "$dir"/f_trajectory.txt 2>/dev/null | head -n 1 || true)
  local frames=0 ate="-"
  if [[ -n $trajectory ]]; then
    awk '!/^#/ && NF == 8 { printf "%.9f %s %s %s %s %s %s %s\n", $1 / 1e9, $2, $3, $4, $5, $6, $7, $8 }' \
      "$trajectory" >"$dir/trajectory.tum"
    frames=$(wc -l <"$dir/trajectory.tum")
    ate=$(ate_orbslam3_mm "$dir/trajectory.tum")
  fi
  echo "$frames $(awk -F, '!/^#/ && NF > 0 { print $NF }' "$stats" | median_p90) ${ate:--}"
}

# One heslam real-time run through the real-time benchmark (its row: label missed frames keyframes
# median p90 local_ba recorded ate wall). Prints: frames-with-pose median p90 ate.
run_heslam() {
  local dir=$out/heslam_$1 row
  LOCKSTEP_REFERENCE=0 HESLAM_BUILD_DIR=${HESLAM_BUILD_DIR:-$root/build} \
    "$root/tools/bench/realtime/realtime_pipeline.sh" "$dataset" "$dir" 1 "$domain" "$heslam_kind" >"$dir.log" 2>&1 ||
    { echo "side_by_side.sh: heslam round $1 failed; see $dir.log" >&2; exit 1; }
  row=$(awk '$1 == "rt_1"' "$dir/table.txt")
  [[ -n $row ]] || { echo "side_by_side.sh: heslam round $1 printed no result; see $dir.log" >&2; exit 1; }
  awk '{ print $8, $5, $6, $9 }' <<<"$row"
}

{
  echo "# $(date -u '+%F %T') UTC, load average $(cut -d' ' -f1-3 /proc/loadavg), dataset $dataset," \
    "$(wc -l <"$times") frames, $([[ $inertial == 1 ]] && echo stereo-inertial || echo stereo)," \
    "ORB-SLAM3 $orbslam3 ($(basename "$settings"))"
  printf "%-6s %-10s %8s %10s %8s %8s\n" round system frames "median ms" "p90 ms" "ATE mm"
} | tee "$out/table.txt"
for round in $(seq 1 "$rounds"); do
  # An assignment, so that a failed run ends the script (set -e) rather than printing an empty row.
  result=$(run_orbslam3 "$round")
  read -r frames median p90 ate <<<"$result"
  printf "%-6s %-10s %8s %10s %8s %8s\n" "$round" ORB-SLAM3 "$frames" "$median" "$p90" "$ate" | tee -a "$out/table.txt"
  result=$(run_heslam "$round")
  read -r frames median p90 ate <<<"$result"
  printf "%-6s %-10s %8s %10s %8s %8s\n" "$round" heslam "$frames" "$median" "$p90" "$ate" | tee -a "$out/table.txt"
done
# heslam's median over ORB-SLAM3's, per round (the figure the speed target is stated in).
ratios=$(awk '!/^#/ && $1 ~ /^[0-9]+$/ { m[$1 " " $2] = $4 }
  END { for (r = 1; ("" r " ORB-SLAM3") in m; ++r)
          if (m[r " ORB-SLAM3"] > 0 && m[r " heslam"] != "-")
            printf "round %d: heslam / ORB-SLAM3 median per frame = %.2f\n", r, m[r " heslam"] / m[r " ORB-SLAM3"] }' \
  "$out/table.txt")
echo "$ratios" | tee -a "$out/table.txt"
