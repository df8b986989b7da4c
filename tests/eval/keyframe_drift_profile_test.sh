#!/usr/bin/env bash
# tools/bench/keyframe_drift_profile.sh on trajectories with a known error: a 10 m straight line whose
# estimate drifts sideways by 2 mm per metre (origin-aligned error 2 mm at each metre, 20 mm at the end),
# keyframes every metre; a second run with the same poses whose fourth keyframe came one frame later.
#   keyframe_drift_profile_test.sh SOURCE_DIR HESLAM_EVAL
set -euo pipefail
script=$1/tools/bench/keyframe_drift_profile.sh
export HESLAM_EVAL=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
awk 'BEGIN { for (i = 0; i <= 100; i++) printf "%.2f %.4f 0 0 0 0 0 1\n", 1600000000 + i / 10, i / 10 }' \
  >"$dir/gt.txt"
awk 'BEGIN {
  print "# frame: body"
  for (i = 0; i <= 100; i++) printf "%.2f %.4f %.6f 0 0 0 0 1\n", 1600000000 + i / 10, i / 10, 0.0002 * i
}' >"$dir/a.txt"
awk '/^#/ || (NR - 2) % 10 == 0' "$dir/a.txt" >"$dir/a.keyframes.txt"
cp "$dir/a.txt" "$dir/b.txt"
awk '/^#/ || NR == 2 || NR == 12 || NR == 22 || NR == 33 || NR == 42' "$dir/b.txt" >"$dir/b.keyframes.txt"
passes=0 failures=0
expect() {  # expect NAME OUTPUT LINE: OUTPUT has LINE
  if grep -qxF -- "$3" <<<"$2"; then
    echo "ok: $1"
    passes=$((passes + 1))
  else
    printf "FAILED: %s: no line '%s' in:\n%s\n" "$1" "$3" "$2"
    failures=$((failures + 1))
  fi
}
one=$("$script" --gt "$dir/gt.txt" "$dir/a.txt")
expect "11 keyframes, 20 mm at the end" "$one" "run 1: $dir/a.txt: ATE rmse 0.006 mm (keyframes: 0.006 mm); \
11 poses, 10.0 m: origin-aligned error at the end 20.0 mm / 0.000 deg"
expect "keyframe 5 at 5 m: 10 mm" "$one" "5 1600000005.000 5.00 10.0 0.000 0.0 0.115"
two=$("$script" --gt "$dir/gt.txt" --step 5 "$dir/a.txt" "$dir/b.txt")
expect "the later keyframe named" "$two" \
  "run 2: first keyframe made at another frame than in run 1: keyframe 3 (stamp 1600000003.10, run 1: 1600000003.00)"
expect "every 5 m" "$two" "5 10.0 0.000 8.0 0.000"
expect "past run 2's end" "$two" "10 20.0 0.000 - -"
if "$script" --gt "$dir/gt.txt" "$dir/missing.txt" 2>"$dir/err"; then
  echo "FAILED: a missing run exits 0"; failures=$((failures + 1))
else
  expect "a missing run is one line" "$(cat "$dir/err")" "keyframe_drift_profile.sh: no trajectory $dir/missing.txt"
fi
echo "$passes passed, $failures failed"
[[ $failures -eq 0 ]]
