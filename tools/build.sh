#!/usr/bin/env bash
# Installs missing packages, configures and builds heslam into build/ (Release unless BUILD_TYPE is set):
#   tools/build.sh [TARGET...]   everything (tests and benchmarks too), or only the targets given
#   tools/build.sh --tests       what tools/test.sh runs: everything but the benchmark executables
#                                (no test runs them; HESLAM_BUILD_BENCHMARKS=OFF)
#   tools/build.sh --demo        what tools/demo.sh runs: the demo's packages only, configured without
#                                the tests and benchmarks, the heslam-demo target
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${HESLAM_BUILD_DIR:-$root/build}
targets=()
if [[ ${1:-} == --demo ]]; then
  [[ $# -eq 1 ]] || { echo "build.sh: --demo takes no targets" >&2; exit 1; }
  "$root/tools/install-deps.sh" demo
  configure=(-DHESLAM_BUILD_TESTS=OFF -DHESLAM_BUILD_BENCHMARKS=OFF)
  targets=(--target heslam-demo)
elif [[ ${1:-} == --tests ]]; then
  [[ $# -eq 1 ]] || { echo "build.sh: --tests takes no targets" >&2; exit 1; }
  "$root/tools/install-deps.sh" all
  configure=(-DHESLAM_BUILD_TESTS=ON -DHESLAM_BUILD_BENCHMARKS=OFF)
else
  "$root/tools/install-deps.sh" all
  configure=(-DHESLAM_BUILD_TESTS=ON -DHESLAM_BUILD_BENCHMARKS=ON)
  for target in "$@"; do targets+=(--target "$target"); done
fi
# HESLAM_CMAKE_ARGS come last: they can override the above.
cmake -S "$root" -B "$build_dir" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" "${configure[@]}" \
  ${HESLAM_CMAKE_ARGS:-} >/dev/null
cmake --build "$build_dir" -j"$(nproc)" "${targets[@]}"
