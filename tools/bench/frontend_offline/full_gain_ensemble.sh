#!/usr/bin/env bash
# The full system (config/pipelines/euroc.yaml, lockstep, as shipped) on cameras exposed apart, as an
# ensemble (gain_ensemble.sh is the tracker-alone version and says why an ensemble): for
# each gain pair L,R, four copies of DATASET made by heslam-photometric -- L,R; 1.02L,R; L,1.02R;
# 0.98L,0.98R -- each run once; prints every run's ATE and keyframes, and the mean ATE per pair with
# its excess over the first pair's mean.
#   tools/bench/frontend_offline/full_gain_ensemble.sh DATASET OUT_DIR [L,R ...]   (default: 1,1 0.5,1.5 0.35,2 1,4)
# K1_OFFSET=DK (environment): added to k1 of both cameras in the copies' sensor.yaml (the lens-model
#   sensitivity of docs/benchmarks.md at 5c1f792, Cameras exposed apart seventh pass, item 7).
# DOMAIN=N (environment, default 196): the DDS domain of the runs.
# FRONTEND_CONFIG=FILE, MAPPER_CONFIG=FILE (environment): the pipeline's frontend_config / mapper_config
#   (default: euroc.yaml's own), e.g. a copy of config/frontend/euroc_mapper.yaml with an option changed.
# Exits 1, naming the run, when a run fails or records fewer poses than the dataset has frames.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)
bin=${HESLAM_BUILD_DIR:-$root/build}/bin
usage="usage: full_gain_ensemble.sh DATASET OUT_DIR [L,R ...]"
dataset=${1:?$usage}
out=${2:?$usage}
shift 2
pairs=("$@")
[[ ${#pairs[@]} -gt 0 ]] || pairs=(1,1 0.5,1.5 0.35,2 1,4)
[[ -d $dataset/mav0 ]] || { echo "full_gain_ensemble.sh: '$dataset' is not an EuRoC folder (no mav0/)" >&2; exit 2; }
k1_offset=${K1_OFFSET:-0}
[[ $k1_offset =~ ^[-+]?[0-9]*\.?[0-9]+$ ]] || { echo "full_gain_ensemble.sh: K1_OFFSET '$k1_offset': expected a number" >&2; exit 2; }
domain=${DOMAIN:-196}
frontend_args=()
[[ -z ${FRONTEND_CONFIG:-} ]] || frontend_args=(--arg "frontend_config=$(realpath "$FRONTEND_CONFIG")")
[[ -z ${MAPPER_CONFIG:-} ]] || frontend_args+=(--arg "mapper_config=$(realpath "$MAPPER_CONFIG")")
frames=$(grep -c -v '^#' "$dataset/mav0/cam0/data.csv")
mkdir -p "$out"

# Adds k1_offset to the first distortion coefficient of a sensor.yaml, in place.
offset_k1() {
  awk -v dk="$k1_offset" '
    /^distortion_coefficients:/ {
      line = $0; sub(/^[^[]*\[/, "", line); sub(/\].*$/, "", line)
      n = split(line, c, ",")
      printf "distortion_coefficients: [%.10g", c[1] + dk
      for (i = 2; i <= n; ++i) printf ", %s", c[i]
      print "]"
      next
    }
    { print }' "$1" > "$1.tmp" && mv "$1.tmp" "$1"
}

printf '%-10s %-44s %s\n' "gains" "runs (ATE mm / keyframes)" "mean ATE"
first_mean=""
for pair in "${pairs[@]}"; do
  [[ $pair =~ ^[0-9.]+,[0-9.]+$ ]] || { echo "full_gain_ensemble.sh: gain pair '$pair': expected L,R" >&2; exit 2; }
  runs=""
  sum=0
  for factors in 1,1 1.02,1 1,1.02 0.98,0.98; do
    gains=$(awk -v p="$pair" -v f="$factors" \
      'BEGIN { split(p, g, ","); split(f, k, ","); printf "%g,%g", g[1] * k[1], g[2] * k[2] }')
    copy=$out/copy_$gains
    if [[ ! -d $copy ]]; then
      "$bin/heslam-photometric" "$dataset" "$copy" --stereo-gain "$gains" > "$out/copy_$gains.log" 2>&1 ||
        { echo "full_gain_ensemble.sh: heslam-photometric failed for $gains: $out/copy_$gains.log" >&2; exit 1; }
      if [[ $k1_offset != 0 ]]; then
        offset_k1 "$copy/mav0/cam0/sensor.yaml"
        offset_k1 "$copy/mav0/cam1/sensor.yaml"
      fi
    fi
    trajectory=$out/$gains.txt
    if ! timeout 600 "$bin/heslam-supervisor" "$root/config/pipelines/euroc.yaml" --domain "$domain" \
        --arg dataset="$copy" --arg output="$trajectory" "${frontend_args[@]}" > "$out/$gains.log" 2>&1; then
      echo "full_gain_ensemble.sh: the run at gains $gains failed: $out/$gains.log" >&2
      exit 1
    fi
    poses=$(grep -c -v '^#' "$trajectory" || true)
    [[ $poses -eq $frames ]] ||
      { echo "full_gain_ensemble.sh: the run at gains $gains recorded $poses of $frames poses: its ATE is not comparable" >&2; exit 1; }
    ate=$("$bin/heslam-eval" ape --gt "$copy/mav0/state_groundtruth_estimate0/data.csv" --est "$trajectory" |
      grep -o -E 'rmse +[0-9.]+' | head -n 1 | awk '{print $2}')
    keyframes=$(grep -c -v '^#' "${trajectory%.txt}.keyframes.txt" || true)
    runs="$runs $ate/$keyframes"
    sum=$(awk -v s="$sum" -v a="$ate" 'BEGIN { print s + a }')
  done
  mean=$(awk -v s="$sum" 'BEGIN { printf "%.3f", s / 4 }')
  [[ -n $first_mean ]] || first_mean=$mean
  excess=$(awk -v m="$mean" -v f="$first_mean" 'BEGIN { printf "%+.1f %%", (m / f - 1) * 100 }')
  printf '%-10s %-44s %s (%s)\n' "$pair" "$runs" "$mean" "$excess"
done
