#!/usr/bin/env bash
# Cameras exposed apart, measured on an ensemble instead of one run: a single run's ATE
# on a 160-frame clip moves by +-8 % under a 2 % change of one camera's gain, which hides a systematic
# effect of a few percent. For each gain pair L,R this runs the tracker alone (heslam-frontend-offline,
# deterministic) four times -- at L,R, 1.02L,R, L,1.02R and 0.98L,0.98R -- and prints the mean SE(3)
# ATE, the mean Sim(3) scale (the factor the estimate must be scaled by: > 1 = too short), and the runs.
#   tools/bench/frontend_offline/gain_ensemble.sh DATASET OUT_DIR [L,R ...]   (default: 1,1 0.5,1.5 0.35,2 1,4)
# EXTRA_ARGS (environment): more heslam-frontend-offline arguments for every run, e.g.
#   EXTRA_ARGS="--drop-stereo-right-above 127" (docs/benchmarks.md at 5c1f792, Cameras exposed apart seventh pass).
# Exits 1, naming the run, if a run fails or tracks fewer frames than the dataset has (the ATE of a
# truncated trajectory is not comparable).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
usage="usage: gain_ensemble.sh DATASET OUT_DIR [L,R ...]"
dataset=${1:?$usage}
out=${2:?$usage}
shift 2
pairs=("$@")
[[ ${#pairs[@]} -gt 0 ]] || pairs=(1,1 0.5,1.5 0.35,2 1,4)
[[ -d $dataset/mav0 ]] || { echo "gain_ensemble.sh: '$dataset' is not an EuRoC folder (no mav0/)" >&2; exit 2; }
truth=$dataset/mav0/state_groundtruth_estimate0/data.csv
[[ -f $truth ]] || { echo "gain_ensemble.sh: $truth: no ground truth" >&2; exit 2; }
extrinsic=(--extrinsic "$dataset/mav0/cam0/sensor.yaml")
read -r -a extra <<< "${EXTRA_ARGS:-}"
mkdir -p "$out"

# The first number after `key` on heslam-eval's output.
number_after() { grep -o -E "$1 +[0-9.]+" | head -n 1 | awk '{print $2}'; }

printf '%-10s %9s %11s  %s\n' "gains" "mean ATE" "mean scale" "runs (ATE mm)"
for pair in "${pairs[@]}"; do
  [[ $pair =~ ^[0-9.]+,[0-9.]+$ ]] || { echo "gain_ensemble.sh: gain pair '$pair': expected L,R" >&2; exit 2; }
  left=${pair%,*}
  right=${pair#*,}
  ates=()
  scales=()
  for factors in 1,1 1.02,1 1,1.02 0.98,0.98; do
    gains=$(awk -v l="$left" -v r="$right" -v f="$factors" \
      'BEGIN { split(f, k, ","); printf "%g,%g", l * k[1], r * k[2] }')
    log=$out/$gains.log
    trajectory=$out/$gains.tum
    if ! "$bin/heslam-frontend-offline" "$dataset" --vocabulary none --stereo-gain "$gains" --output "$trajectory" \
        "${extra[@]}" > "$log" 2>&1; then
      echo "gain_ensemble.sh: the run at gains $gains failed: $log" >&2
      exit 1
    fi
    if ! grep -q -E "([0-9]+) frames, \1 tracked" "$log"; then
      echo "gain_ensemble.sh: the run at gains $gains lost frames ($(grep -o -E '[0-9]+ frames, [0-9]+ tracked' "$log")): its ATE is not comparable" >&2
      exit 1
    fi
    ates+=("$("$bin/heslam-eval" ape --gt "$truth" "${extrinsic[@]}" --est "$trajectory" | number_after rmse)")
    scales+=("$("$bin/heslam-eval" ape --gt "$truth" "${extrinsic[@]}" --est "$trajectory" --align sim3 | number_after scale)")
  done
  printf '%-10s %9s %11s  %s\n' "$pair" \
    "$(printf '%s\n' "${ates[@]}" | awk '{ s += $1 } END { printf "%.3f", s / NR }')" \
    "$(printf '%s\n' "${scales[@]}" | awk '{ s += $1 } END { printf "%.4f", s / NR }')" "${ates[*]}"
done
