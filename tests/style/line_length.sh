#!/usr/bin/env bash
# No line of C++ source over 120 columns (.clang-format's ColumnLimit; tools/format.sh applies it).
# usage: line_length.sh SOURCE_DIR
set -euo pipefail
root=$1
long=$(find "$root/components" "$root/runtime" "$root/tools" "$root/tests" "$root/idl" \
         \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) -print0 |
       xargs -0 awk 'length > 120 { printf "%s:%d: %d columns\n", FILENAME, FNR, length }')
if [[ -n $long ]]; then
  echo "$long"
  echo "style: $(wc -l <<<"$long") lines over 120 columns (run tools/format.sh)"
  exit 1
fi
echo "style: no source line over 120 columns"
