#!/usr/bin/env bash
# Installs the Debian packages heslam needs, only those that are missing, without recommended ones:
#   tools/install-deps.sh [demo|all]   demo: what tools/demo.sh needs; all (default): tools/test.sh's too.
# Used by tools/build.sh so a fresh Debian 12 machine works with one command.
set -euo pipefail

# demo: what tools/demo.sh builds and runs (the heslam-demo target); all: everything, for tools/test.sh.
set_name=${1:-all}
demo_packages=(
  build-essential cmake pkg-config ccache
  cyclonedds-dev cyclonedds-tools
  libopencv-dev libopencv-viz-dev
  opencv-doc  # its photographs train the default vocabulary (tools/train-vocabulary.sh)
  zlib1g-dev
  libeigen3-dev libceres-dev
)
test_packages=(
  iceoryx  # iox-roudi: image_transport shm (docs/topics.md) and its pipeline test
  xvfb     # the viewer's window tests
  openssl  # DDS Security material (heslam-security) and its tests
  googletest libgtest-dev libbenchmark-dev
)
case $set_name in
  demo) packages=("${demo_packages[@]}") ;;
  all) packages=("${demo_packages[@]}" "${test_packages[@]}") ;;
  *) echo "install-deps.sh: unknown package set '$set_name' (demo or all)" >&2; exit 1 ;;
esac

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "heslam: installing missing Debian packages: ${missing[*]}"
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  if ! command -v sudo >/dev/null; then
    echo "heslam: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
  sudo_cmd=(sudo)
fi
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
