#!/usr/bin/env bash
# The test command: install missing packages, build what the tests need (tools/build.sh --tests: all
# but the benchmark executables), run the whole ctest suite. .ci/run calls exactly this script.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/build.sh" --tests
build_dir=${HESLAM_BUILD_DIR:-$root/build}
cd "$build_dir"
# ctest starts the longest tests first when it knows their times (Testing/Temporary/CTestCostData.txt,
# which every run updates); a fresh build has none and would start them in declaration order, the
# longest pipelines possibly last on one core. It starts from the times in tests/ctest_costs.txt
# (docs/testing.md, "Parallel runs"); unknown or renamed tests only lose their place in the order.
costs=Testing/Temporary/CTestCostData.txt
if [[ ! -s $costs ]]; then
  mkdir -p "$(dirname "$costs")"
  cp "$root/tests/ctest_costs.txt" "$costs"
fi
ctest --output-on-failure --timeout 900 -j"$(nproc)" "$@"
