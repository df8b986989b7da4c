#!/usr/bin/env bash
# Installs missing packages, configures and builds heslam into build/ (Release unless BUILD_TYPE is set):
# everything, or only the targets given (tools/demo.sh builds heslam-demo, what it runs).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/install-deps.sh"
build_dir=${HESLAM_BUILD_DIR:-$root/build}
cmake -S "$root" -B "$build_dir" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" ${HESLAM_CMAKE_ARGS:-} >/dev/null
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build "$build_dir" -j"$(nproc)" "${targets[@]}"
