#!/usr/bin/env bash
# The whole system in real time: runs the real-time pipeline (replay at rate 1 + frontend +
# local mapper + loop closer + recorder) RUNS times over a dataset, and once in lockstep for reference,
# and prints per run and as median / worst over the runs: frames missed by the frontend, its per-frame
# time (stage "total", median / p90), the local BA per keyframe (median), the keyframes the frontend
# made (and their ratio to the lockstep run's), frames recorded and, with ground truth, the ATE.
# Figures come from the components' end-of-run summaries in their logs (OUT_DIR/logs_*/NAME.log).
#   tools/bench/realtime/realtime_pipeline.sh DATASET OUT_DIR [RUNS] [DOMAIN] [euroc|euroc_inertial|kitti]
# euroc: config/pipelines/euroc_realtime.yaml against euroc.yaml (EuRoC folder, 20 Hz); euroc_inertial:
# euroc_inertial_realtime.yaml against euroc_inertial.yaml (the folder needs mav0/imu0/);
# kitti: kitti_realtime.yaml against kitti.yaml (a KITTI sequence folder DIR/sequences/NN, e.g. heslam-synth --preset street --format kitti, 10 Hz; ATE against DIR/poses/NN.txt).
# PRELOAD_MB=N (environment): real-time runs decode the images before frame 0 (replay --preload N), so
# that PNG decoding (about a quarter of the pipeline's CPU on MH01) does not compete with the system.
# LOCKSTEP_REFERENCE=0 (environment): no lockstep reference run (tools/bench/side_by_side.sh times the
# real-time runs only).
# OCCUPANCY=1 (environment): every run with --arg occupancy=heslam-occupancy, and per run one more line:
# the keyframe clouds it fused of the keyframes made, its disparity (rectify, HE, SGBM, cloud) and fusion
# per keyframe (median wall and CPU, from its log) against the median keyframe interval (the recorded
# keyframe trajectory's stamps). OCCUPANCY_CONFIG=FILE: its --arg occupancy_config.
# Not repeatable run to run (real time depends on the machine's load): report the load with the figures.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
usage="usage: realtime_pipeline.sh DATASET OUT_DIR [RUNS] [DOMAIN] [euroc|euroc_inertial|kitti]"
dataset=${1:?$usage}
out=${2:?$usage}
runs=${3:-5}
domain=${4:-217}
kind=${5:-euroc}
case $kind in
  euroc | euroc_inertial | kitti) ;;
  *) echo "realtime_pipeline.sh: kind '$kind': expected euroc, euroc_inertial or kitti" >&2; exit 2 ;;
esac
[[ -d $dataset ]] || { echo "realtime_pipeline.sh: dataset '$dataset' is not a folder" >&2; exit 2; }
[[ $runs =~ ^[1-9][0-9]*$ ]] || { echo "realtime_pipeline.sh: RUNS '$runs': expected a positive integer" >&2; exit 2; }
mkdir -p "$out"
preload_mb=${PRELOAD_MB:-0}
[[ $preload_mb =~ ^[0-9]+$ ]] || { echo "realtime_pipeline.sh: PRELOAD_MB '$preload_mb': expected a whole number of MB" >&2; exit 2; }

# One number from a log line matching `pattern`, by a sed expression; "-" when absent.
field() {
  local file=$1 pattern=$2 expression=$3 value
  value=$(grep -h -E "$pattern" "$file" 2>/dev/null | tail -n 1 | sed -E "$expression" || true)
  [[ -n $value ]] && echo "$value" || echo "-"
}

# ATE rmse in mm of a trajectory, or "-" without ground truth (EuRoC: the state ground truth; KITTI:
# DATASET/../../poses/NN.txt with DATASET/times.txt, as heslam-synth --format kitti writes them).
ate_mm() {
  local trajectory=$1 rmse gt gt_args
  if [[ $kind == euroc* ]]; then
    gt=$dataset/mav0/state_groundtruth_estimate0/data.csv
    gt_args=(--gt "$gt")
  else
    gt=$(dirname "$(dirname "$dataset")")/poses/$(basename "$dataset").txt
    gt_args=(--gt "$gt" --gt-times "$dataset/times.txt" --gt-format kitti)
  fi
  [[ -f $gt && -s $trajectory ]] || { echo "-"; return; }
  # heslam-eval prints "rmse VALUE UNIT" with the unit it finds readable (m, cm, mm).
  # The trajectory's header names its frame (body by default), which heslam-eval matches to the ground truth.
  rmse=$("$bin/heslam-eval" ape "${gt_args[@]}" --est "$trajectory" 2>/dev/null |
    grep -m1 -E '^ *rmse' | awk '{ s = $3 == "m" ? 1000 : $3 == "cm" ? 10 : $3 == "mm" ? 1 : $3 == "um" ? 0.001 : -1
                                   if (s > 0) printf "%.2f", $2 * s }' || true)
  [[ -n $rmse ]] && echo "$rmse" || echo "-"
}

# Runs one pipeline; prints one row: label missed frames kf median p90 local_ba recorded ate wall.
run_pipeline() {
  local pipeline=$1 label=$2 logs=$out/logs_$2 start wall extra=()
  [[ $pipeline == *_realtime.yaml ]] && extra=(--arg preload_mb="$preload_mb")
  [[ ${OCCUPANCY:-0} == 1 ]] && extra+=(--arg occupancy=heslam-occupancy)
  [[ -n ${OCCUPANCY_CONFIG:-} ]] && extra+=(--arg occupancy_config="$OCCUPANCY_CONFIG")
  rm -rf "$logs" "$out/$label.txt"*
  start=$(date +%s.%N)
  if ! "$bin/heslam-supervisor" "$root/config/pipelines/$pipeline" --domain "$domain" --log-dir "$logs" \
    --arg dataset="$dataset" --arg output="$out/$label.txt" "${extra[@]}" >"$out/$label.supervisor.log" 2>&1; then
    echo "realtime_pipeline.sh: $pipeline run $label failed; see $out/$label.supervisor.log and $logs/" >&2
    exit 1
  fi
  wall=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
  local fe=$logs/frontend.log mapper=$logs/local_mapper.log
  local frames keyframes missed total_median total_p90 ba_median recorded
  frames=$(field "$fe" 'processed [0-9]+ frames' 's/.*processed ([0-9]+) frames.*/\1/')
  keyframes=$(field "$fe" 'processed [0-9]+ frames' 's/.*, ([0-9]+) keyframes.*/\1/')
  missed=$(field "$fe" 'frames missed:' 's/.* ([0-9]+) frames missed:.*/\1/')
  [[ $missed == - ]] && missed=0
  total_median=$(field "$fe" 'stage total ' 's/.*median +([0-9.]+) ms.*/\1/')
  total_p90=$(field "$fe" 'stage total ' 's/.*p90 +([0-9.]+) ms.*/\1/')
  ba_median=$(field "$mapper" 'stage local_ba ' 's/.*median +([0-9.]+) ms.*/\1/')
  recorded=$( [[ -f $out/$label.txt ]] && grep -cv '^#' "$out/$label.txt" || echo 0)
  printf "%-10s %6s %6s %9s %10s %10s %12s %9s %8s %7s\n" "$label" "$missed" "$frames" "$keyframes" \
    "$total_median" "$total_p90" "$ba_median" "$recorded" "$(ate_mm "$out/$label.txt")" "$wall"
  [[ ${OCCUPANCY:-0} == 1 ]] && occupancy_line "$label" "$logs/occupancy.log" "$out/$label.keyframes.txt"
  return 0
}

# "#   occupancy LABEL: C/K clouds, disparity W ms (cpu C ms), fusion ..., keyframe interval I ms".
occupancy_line() {
  local label=$1 log=$2 keyframes=$3 clouds made interval
  clouds=$(field "$log" 'keyframe clouds fused' 's/.*map: ([0-9]+) keyframe clouds fused.*/\1/')
  made=$( [[ -f $keyframes ]] && grep -cv '^#' "$keyframes" || echo "-")
  # Median gap between consecutive keyframe stamps (TUM: seconds in column 1).
  interval=$( [[ -f $keyframes ]] && grep -v '^#' "$keyframes" | awk '{ print $1 }' | sort -g |
    awk 'NR > 1 { print ($1 - p) * 1000 } { p = $1 }' | sort -g |
    awk '{ a[NR] = $1 } END { if (NR) printf "%.0f", NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2; else print "-" }' || echo "-")
  stage() { field "$log" "stage $1 " 's/.*median +([0-9.]+) ms.*/\1/'; }
  echo "#   occupancy $label: $clouds/$made keyframe clouds, disparity $(stage disparity) ms (cpu $(stage disparity_cpu)), fusion $(stage fusion) ms (cpu $(stage fusion_cpu)), median keyframe interval $interval ms, final rebuild $(stage final_rebuild) ms"
}

header() {
  printf "%-10s %6s %6s %9s %10s %10s %12s %9s %8s %7s\n" run missed frames keyframes "fe med ms" "fe p90 ms" \
    "local BA ms" recorded "ATE mm" "wall s"
}

echo "# $(date -u '+%F %T') UTC, load average $(cut -d' ' -f1-3 /proc/loadavg), $kind, dataset $dataset, replay preload ${preload_mb} MB"
header | tee "$out/table.txt"
[[ ${LOCKSTEP_REFERENCE:-1} == 0 ]] || run_pipeline "${kind}.yaml" lockstep | tee -a "$out/table.txt"
for run in $(seq 1 "$runs"); do
  run_pipeline "${kind}_realtime.yaml" "rt_$run" | tee -a "$out/table.txt"
done
echo "# load average at the end $(cut -d' ' -f1-3 /proc/loadavg)"

# Median and worst of the real-time runs (worst: most missed, fewest frames, most keyframes, slowest).
awk -v runs="$runs" '
  function sort(a, n,   i, j, t) { for (i = 2; i <= n; ++i) for (j = i; j > 1 && a[j - 1] > a[j]; --j) { t = a[j]; a[j] = a[j - 1]; a[j - 1] = t } }
  function median(a, n) { sort(a, n); return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2 }
  $1 == "lockstep" { lock_kf = $4 }
  $1 ~ /^rt_/ { ++n; miss[n] = $2; fr[n] = $3; kf[n] = $4; med[n] = $5; p90[n] = $6; ba[n] = $7 }
  END {
    if (n == 0) exit 1
    for (i = 1; i <= n; ++i) { m1[i] = miss[i]; k1[i] = kf[i]; d1[i] = med[i]; q1[i] = p90[i]; b1[i] = ba[i]; f1[i] = fr[i] }
    printf "median of %d real-time runs: missed %s, frames %s, keyframes %s (%.2fx lockstep %s), frontend %.2f / p90 %.2f ms, local BA %.2f ms\n",
      n, median(m1, n), median(f1, n), median(k1, n), (lock_kf > 0 ? median(k1, n) / lock_kf : 0), lock_kf,
      median(d1, n), median(q1, n), median(b1, n)
    printf "worst: missed %s, frames %s, keyframes %s (%.2fx), frontend %.2f / p90 %.2f ms, local BA %.2f ms\n",
      m1[n], f1[1], k1[n], (lock_kf > 0 ? k1[n] / lock_kf : 0), d1[n], q1[n], b1[n]
  }' "$out/table.txt"
