#!/usr/bin/env bash
# How a run's error grows along its path: the keyframe trajectory the recorder writes next to a run's
# trajectory (FILE stem + .keyframes.txt) against the ground truth, keyframe by keyframe, aligned on
# the first keyframe (the drift accumulated since the start) and by SE(3) over the whole run (the ATE's
# own alignment). With several runs (builds, or settings, on one render) it puts them side by side
# every --step metres of ground-truth path and names the first keyframe each made at another frame
# than the first run: where two runs of one render part (from there on their errors are two samples).
#   tools/bench/keyframe_drift_profile.sh --gt GT [--extrinsic cam0/sensor.yaml] [--step M] [--every N]
#                                         [--frames] RUN.txt [RUN.txt ...]
# GT: a ground truth with time stamps as heslam-eval reads it (EuRoC data.csv, TUM). --extrinsic is
# used only for a run recorded in another frame than the body (its header has no 'frame: body').
# HESLAM_EVAL: the heslam-eval to use (default: this checkout's build/bin/heslam-eval).
# One run: one row per keyframe (every N-th with --every), columns
#   kf  stamp_s  path_m  origin_mm  origin_deg  se3_mm  se3_deg
# Several runs: one row per --step metres (default 2), each run's origin-aligned error (mm / deg) at
# its last keyframe up to that path length ('-' past a run's end).
# --frames: every frame of the trajectories instead of their keyframes.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
eval_bin=${HESLAM_EVAL:-$here/build/bin/heslam-eval}
gt="" extrinsic="" step=2 every=1 frames=false runs=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --gt) gt=$2; shift 2 ;;
    --extrinsic) extrinsic=$2; shift 2 ;;
    --step) step=$2; shift 2 ;;
    --every) every=$2; shift 2 ;;
    --frames) frames=true; shift ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "keyframe_drift_profile.sh: unknown argument '$1'" >&2; exit 2 ;;
    *) runs+=("$1"); shift ;;
  esac
done
fail() { echo "keyframe_drift_profile.sh: $1" >&2; exit "${2:-1}"; }
[[ -n $gt && ${#runs[@]} -gt 0 ]] || fail "usage: --gt GT RUN.txt [RUN.txt ...]" 2
[[ -f $gt ]] || fail "no ground truth file $gt"
[[ -x $eval_bin ]] || fail "no $eval_bin (build heslam-eval)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# errors RUN_INDEX ALIGN: heslam-eval's per-pair rows of that run (est_row stamp err dx dy dz rot path).
errors() {
  local run=${runs[$1]} est
  if $frames; then est=$run; else est=${kf_files[$1]}; fi
  local args=(ape --gt "$gt" --est "$est" --align "$2" --errors "$tmp/$1.$2")
  if [[ -n $extrinsic ]] && ! grep -q 'frame: body' "$est"; then args+=(--extrinsic "$extrinsic"); fi
  "$eval_bin" "${args[@]}" >"$tmp/$1.$2.out" 2>&1 || { cat "$tmp/$1.$2.out" >&2; exit 1; }
}

kf_files=()
for run in "${runs[@]}"; do
  [[ -f $run ]] || fail "no trajectory $run"
  kf_files+=("${run%.*}.keyframes.txt")
  [[ -f ${kf_files[-1]} ]] || fail "no ${kf_files[-1]} (the recorder writes it next to $run)"
done
for i in "${!runs[@]}"; do
  errors "$i" origin
  errors "$i" se3
  se3_rmse=$(awk '!/^#/ { s += $3 * $3; n++ } END { printf "%.3f", 1e3 * sqrt(s / n) }' "$tmp/$i.se3")
  args=(ape --gt "$gt" --est "${runs[$i]}" --full-precision)
  if [[ -n $extrinsic ]] && ! grep -q 'frame: body' "${runs[$i]}"; then args+=(--extrinsic "$extrinsic"); fi
  frames_rmse=$("$eval_bin" "${args[@]}" 2>/dev/null | awk '/rmse/ { printf "%.3f", $2 * 1000 }')
  last=$(awk '!/^#/ { e = $3; r = $7; p = $8; n++ }
    END { printf "%d poses, %.1f m: origin-aligned error at the end %.1f mm / %.3f deg", n, p, 1e3 * e, r }' \
    "$tmp/$i.origin")
  printf 'run %d: %s: ATE rmse %s mm (keyframes: %s mm); %s\n' "$((i + 1))" "${runs[$i]}" "${frames_rmse:-?}" \
    "$se3_rmse" "$last"
done

# Where a later run's keyframe decisions leave the first run's: its first keyframe made at another
# frame (the poses themselves cannot say it, as a recorded pose follows its keyframe's final pose).
if [[ ${#runs[@]} -gt 1 ]]; then
  for i in $(seq 1 $((${#runs[@]} - 1))); do
    awk -v name="run $((i + 1))" '
      FNR == NR { if (!/^#/) a[++n] = $1; next }
      !/^#/ {
        m++
        if (!(m in a) || a[m] != $1) {
          printf "%s: first keyframe made at another frame than in run 1: keyframe %d (stamp %s, run 1: %s)\n",
                 name, m - 1, $1, (m in a) ? a[m] : "none"
          found = 1
          exit
        }
      }
      END { if (!found) printf "%s: the same keyframe stamps as run 1 (%d keyframes)\n", name, m }' \
      "${kf_files[0]}" "${kf_files[$i]}"
  done
fi

if [[ ${#runs[@]} -eq 1 ]]; then
  echo "kf stamp_s path_m origin_mm origin_deg se3_mm se3_deg"
  paste -d' ' <(grep -v '^#' "$tmp/0.origin") <(grep -v '^#' "$tmp/0.se3") |
    awk -v every="$every" '(NR - 1) % every == 0 {
      printf "%d %.3f %.2f %.1f %.3f %.1f %.3f\n", $1, $2, $8, 1e3 * $3, $7, 1e3 * $11, $15
    }'
  exit 0
fi

# Several runs: each run's error at its last pose up to every step of path.
header="path_m"
for i in "${!runs[@]}"; do header+=" run$((i + 1))_mm run$((i + 1))_deg"; done
echo "$header"
files=()
for i in "${!runs[@]}"; do files+=("$tmp/$i.origin"); done
awk -v step="$step" -v runs="${#runs[@]}" '
  FNR == 1 { r++ }
  # bin b holds the poses with a path in (b step, (b + 1) step]; the first pose is in bin 0
  !/^#/ {
    bin = $8 > 0 ? int(($8 - 1e-9) / step) : 0
    err[r, bin] = $3; rot[r, bin] = $7; last[r] = bin
    if (bin > top) top = bin
  }
  END {
    for (b = 0; b <= top; b++) {
      line = sprintf("%g", (b + 1) * step)
      for (k = 1; k <= runs; k++) {
        if ((k, b) in err) { e[k] = err[k, b]; o[k] = rot[k, b] }
        line = line (b > last[k] ? " - -" : sprintf(" %.1f %.3f", 1e3 * e[k], o[k]))
      }
      print line
    }
  }' "${files[@]}"
