#!/usr/bin/env bash
# Builds heslam with a sanitizer into its own build folder and runs the tests that sanitizer is for.
#
#   tools/sanitize.sh address   # ASan + UBSan: every unit test and the full system end to end
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

# ASan + UBSan: every unit-test executable (runtime, supervisor, vision, place, tracking on real
# images, mapping, loop geometry, eval, synth, dataset, replay, spy, security) and one multi-process
# end-to-end executable: the full system (replay, frontend, local mapper, loop closer, recorder under
# the supervisor, every process built with ASan) on MH01 and the synthetic room. The other
# end-to-end executables add build time (an ASan link each) and the same code paths.
asan_targets=(heslam_runtime_tests heslam_runtime_shutdown_tests heslam_runtime_component_tests
  heslam_supervisor_unit_tests heslam_pipeline_hosts_tests heslam_test_place_vocabulary
  heslam_test_place_database heslam_messages_unit_test heslam_frontend_unit_test heslam_frame_processor_test
  heslam_mapping_tests
  heslam_test_vision_calibration heslam_test_vision_matching heslam_test_vision_orb
  heslam_test_vision_stereo heslam_test_vision_he test_eval heslam_test_tracking_synthetic
  heslam_test_tracking_euroc heslam_test_loop heslam_dataset_test heslam_replay_core_test
  heslam_spy_core_test heslam_local_mapper_unit_test heslam_synth_tests heslam_security_tests
  heslam_loop_closer_unit_test heslam_loop_closer_e2e_test heslam-loop-closer heslam-local-mapper)
# Under ASan the multi-process tests run 2-4x slower: the long sequences (corridor loop, a loop
# closer started by hand mid-run) are left out; the full system on MH01 and the room stay.
# The real-time pipelines are named one by one: a bare "RealTime" also left out unit tests
# (MirrorOfARealTimeRun.*, ReplayPacer.RealTimeDoubleSpeedAndFlatOut) until 2026-11-26.
# ctest lists a test executable that this build did not make as one test named TARGET_NOT_BUILT;
# the pattern below leaves those out (they are the executables outside asan_targets).
asan_excluded='Corridor|Street|Kidnapped|Teleported|Soak|Mh01RealTime|MultiHost\.RealTime|PipelineOutcomeRealTime|SpyHzMeasuresRealTime|FullSystemDeterministic|StartedByHand|_NOT_BUILT'
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

# The default vocabulary: the normal build's copy when there is one (training it with sanitized
# binaries takes 5-15x longer and gives the same file), else trained in this build.
vocabulary() { # build_dir
  local trained=$root/build/vocabulary/heslam_orb.hvoc
  if [[ -s $trained ]]; then
    mkdir -p "$1/vocabulary" && cp "$trained" "$1/vocabulary/"
  else
    cmake --build "$1" -j"$(nproc)" --target heslam-default-vocabulary
  fi
}

run_address() {
  local dir=$build_root/build-asan
  configure "$dir" address
  cmake --build "$dir" -j"$(nproc)" --target "${asan_targets[@]}"
  vocabulary "$dir"
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
  vocabulary "$dir"
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
