#!/usr/bin/env bash
# The test command: install missing packages, build, run the whole ctest suite.
# .ci/run calls exactly this script.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/build.sh"
build_dir=${HESLAM_BUILD_DIR:-$root/build}
cd "$build_dir"
ctest --output-on-failure --timeout 900 -j"$(nproc)" "$@"
