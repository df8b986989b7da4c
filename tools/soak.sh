#!/usr/bin/env bash
# Fault-injection soak of the full system: N lockstep runs of config/pipelines/euroc.yaml
# on ../shared/data/euroc_mh01_handheld, each with several kill -9 of random components at seeded
# moments (single, two within 0.5 s, all but the supervisor). Every run must end rc 0 with 160/160
# poses and an ATE within 1.2x of an undisturbed run. It is the suite's
# Recovery.SoakRandomKillsLoseNoFrameAndKeepTheAccuracy (2 runs in CI), longer:
#
#   tools/soak.sh [--runs N] [--seed S] [--kills K]   # defaults: 20 runs, seed from the clock, 3 kills per run
#   tools/soak.sh --seed 1234 --runs 1                # replay the run a failure printed
#
# Each run prints its seed and plan first ("[ soak ] run i seed S: frame F: a +120ms b; ..."), then its
# result; logs of failed runs stay in /tmp/heslam_test_recovery_soak_<pid>. Needs a build
# (tools/build.sh); a run takes about as long as one lockstep run of the clip plus the restarts.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${HESLAM_BUILD_DIR:-$root/build}
runs=20
seed=$(date +%s)
kills=3
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --kills) kills=$2; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "soak.sh: unknown argument '$1' (expected --runs N, --seed S, --kills K)" >&2; exit 1 ;;
  esac
done
for value in "$runs" "$seed" "$kills"; do
  [[ "$value" =~ ^[0-9]+$ ]] || { echo "soak.sh: '$value' is not a non-negative integer" >&2; exit 1; }
done
test_bin="$build_dir/tests/heslam_recovery_e2e_test"
[ -x "$test_bin" ] || { echo "soak.sh: $test_bin not found; build first (tools/build.sh)" >&2; exit 1; }
echo "soak: $runs runs from seed $seed, $kills kill events per run"
HESLAM_SOAK_RUNS=$runs HESLAM_SOAK_SEED=$seed HESLAM_SOAK_KILLS=$kills \
  exec "$test_bin" --gtest_filter='Recovery.SoakRandomKillsLoseNoFrameAndKeepTheAccuracy'
