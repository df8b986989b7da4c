#!/usr/bin/env bash
# Builds heslam with a sanitizer into its own build folder and runs the tests that sanitizer is for.
#
#   tools/sanitize.sh address   # ASan + UBSan: every unit test and multi-process end-to-end runs
#   tools/sanitize.sh thread    # TSan: the code that runs threads (runtime, pair worker, global BA)
#   tools/sanitize.sh all       # both, one after the other
#
# Extra arguments go to ctest (e.g. -R Config). Exit code: 0 only when every selected test passed
# with no sanitizer report. Build folders: build-asan/, build-tsan/ (HESLAM_SANITIZE_BUILD_ROOT
# moves them). Measured times and findings: docs/testing.md.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
mode=${1:-}
[[ $# -gt 0 ]] && shift
build_root=${HESLAM_SANITIZE_BUILD_ROOT:-$root}

# Under ASan the multi-process tests run 2-4x slower; these are the long sequences (corridor loop,
# street, kidnapping, soak) whose behaviour the short runs below already cover under ASan.
asan_excluded='Corridor|Street|Kidnapped|Teleported|Soak|RealTime|FullSystemDeterministic'
# TSan: the test executables whose code starts threads — the runtime (status heartbeat, shutdown
# watcher, supervisor with real processes), the right-image worker of the stereo pipeline (vision
# tests and the frontend on real images), the loop closer's global BA thread — and one lockstep run
# of the whole mapper pipeline on real images (every process built with TSan).
tsan_targets=(heslam_runtime_tests heslam_runtime_shutdown_tests heslam_runtime_component_tests
  heslam_supervisor_tests heslam-supervisor heslam-test-talker heslam_test_vision_stereo
  heslam_test_tracking_euroc heslam_loop_closer_unit_test heslam_local_mapper_e2e_test
  heslam-frontend heslam-local-mapper heslam-replay heslam-recorder)
tsan_tests='^(Config|CommonArgs|Stats|Qos|PubSub|LogThrottle|Participant|Shutdown|Component|ComponentErrors|SupervisorTest|StereoMatcher|StereoFeaturePipeline|LoopCloserGlobalBa)\.|^TrackingEuroc\.Mh01Handheld|^LocalMapperEndToEnd\.EurocMh01Lockstep'

fail() { echo "sanitize: $*" >&2; exit 1; }

configure() { # build_dir sanitizer
  "$root/tools/install-deps.sh"
  cmake -S "$root" -B "$1" -DCMAKE_BUILD_TYPE=Release -DHESLAM_SANITIZE="$2" \
    -DHESLAM_BUILD_BENCHMARKS=OFF >/dev/null
}

run_address() {
  local dir=$build_root/build-asan
  configure "$dir" address
  cmake --build "$dir" -j"$(nproc)"
  # halt_on_error: a report fails the test; detect_leaks: leaks are reports too.
  export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:abort_on_error=0
  export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
  (cd "$dir" && ctest --output-on-failure --timeout 1800 -j"$(nproc)" -E "$asan_excluded" "$@") ||
    fail "address: a test failed or a sanitizer reported (see above)"
  echo "sanitize: address: all selected tests passed, no ASan/UBSan report"
}

run_thread() {
  local dir=$build_root/build-tsan
  configure "$dir" thread
  cmake --build "$dir" -j"$(nproc)" --target "${tsan_targets[@]}"
  # libddsc is not instrumented: its own threads' accesses are invisible to TSan, which then
  # reports races inside it that are synchronised by its atomics. Those frames are suppressed; a
  # race with one of our frames on either side is still reported.
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/tools/tsan.supp"
  (cd "$dir" && ctest --output-on-failure --timeout 1800 -j"$(nproc)" -R "$tsan_tests" "$@") ||
    fail "thread: a test failed or TSan reported (see above)"
  echo "sanitize: thread: all selected tests passed, no TSan report"
}

case $mode in
  address) run_address "$@" ;;
  thread) run_thread "$@" ;;
  all) run_address "$@"; run_thread "$@" ;;
  *) fail "usage: tools/sanitize.sh address|thread|all [ctest arguments]" ;;
esac
