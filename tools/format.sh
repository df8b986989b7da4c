#!/usr/bin/env bash
# Formats heslam's C++ sources with .clang-format (Google style, 120 columns). Needs clang-format
# (Debian: apt-get install clang-format); not part of the build or the test command.
#   tools/format.sh            format every tracked .cpp/.hpp in place
#   tools/format.sh --check    list the files that would change, exit 1 if any
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
formatter=$(command -v clang-format-14 || command -v clang-format || true)
if [[ -z $formatter ]]; then
  echo "tools/format.sh: clang-format not found (apt-get install clang-format)" >&2
  exit 1
fi
mapfile -t files < <(git ls-files '*.cpp' '*.hpp')
if [[ ${1:-} == --check ]]; then
  changed=0
  for file in "${files[@]}"; do
    if ! "$formatter" --dry-run -Werror "$file" >/dev/null 2>&1; then echo "$file"; changed=1; fi
  done
  exit $changed
fi
"$formatter" -i "${files[@]}"
