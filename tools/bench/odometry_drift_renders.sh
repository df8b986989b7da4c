#!/usr/bin/env bash
# The open-loop drift of the full system without a loop closer (frontend + local mapper, lockstep,
# --arg loop_closer=none) over several renders of one heslam-synth preset: one render's ATE is one
# sample of a chaotic quantity (a change of the order in which the frontend applies a batch of map
# states moves it by up to half; docs/benchmarks.md, "Open-loop drift"), so compare builds on the
# mean and on the per-render pairs, not on one render.
#   tools/bench/odometry_drift_renders.sh [--preset corridor_loop] [--frames 960] [--seeds "1 2 3 4 5 6 7"]
#                                         [--out DIR] [--domain N] [--root CHECKOUT]
# --root runs another checkout's build (e.g. a worktree at an older commit) on the same renders.
# Prints one line per seed (ATE rmse, keyframes) and the mean; renders are kept in DIR/renders.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
root=$here preset=corridor_loop frames=960 seeds="1 2 3 4 5 6 7" out=/tmp/heslam-drift domain=${HESLAM_DOMAIN:-auto}
while [[ $# -gt 0 ]]; do
  case $1 in
    --preset) preset=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --seeds) seeds=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --domain) domain=$2; shift 2 ;;
    --root) root=$(cd "$2" && pwd); shift 2 ;;
    *) echo "odometry_drift_renders.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
bin=$here/build/bin
runs=$out/runs_$(cd "$root" && git rev-parse --short HEAD)
mkdir -p "$out/renders" "$runs"
sum=0 n=0
for seed in $seeds; do
  render=$out/renders/${preset}_${frames}_s$seed
  if [[ ! -f $render/.complete ]]; then
    rm -rf "$render"
    "$bin/heslam-synth" --preset "$preset" --frames "$frames" --seed "$seed" --threads 2 --no-events --quiet \
      --out "$render" >/dev/null
    touch "$render/.complete"
  fi
  run=$runs/s$seed
  rm -rf "$run"; mkdir -p "$run"
  if ! (cd "$root" && build/bin/heslam-supervisor config/pipelines/synth.yaml --domain "$domain" \
        --arg dataset="$render" --arg output="$run/t.txt" --arg loop_closer=none >"$run/log" 2>&1); then
    echo "seed $seed: the run failed: $(tail -1 "$run/log")" >&2
    exit 1
  fi
  extrinsic=()
  grep -q 'frame: body' "$run/t.txt" || extrinsic=(--extrinsic "$render/mav0/cam0/sensor.yaml")
  ate=$("$bin/heslam-eval" ape "${extrinsic[@]}" --est "$run/t.txt" \
        --gt "$render/mav0/state_groundtruth_estimate0/data.csv" --full-precision | awk '/rmse/ {print $2 * 1000}')
  keyframes=$(grep -vc '^#' "$run/t.keyframes.txt")
  printf '%s seed %s: ATE rmse %.3f mm, %d keyframes\n' "$preset" "$seed" "$ate" "$keyframes"
  sum=$(awk -v s="$sum" -v a="$ate" 'BEGIN {print s + a}')
  n=$((n + 1))
done
awk -v s="$sum" -v n="$n" -v p="$preset" 'BEGIN {printf "%s: mean ATE rmse over %d renders %.1f mm\n", p, n, s / n}'
