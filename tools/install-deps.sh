#!/usr/bin/env bash
# Installs the Debian packages heslam needs, only those that are missing.
# Used by tools/demo.sh and tools/test.sh so a fresh Debian 12 machine works with one command.
set -euo pipefail

packages=(
  build-essential cmake pkg-config ccache
  cyclonedds-dev cyclonedds-tools
  iceoryx  # iox-roudi: image_transport shm (docs/topics.md) and its pipeline test
  libopencv-dev opencv-doc libopencv-viz-dev
  xvfb
  zlib1g-dev
  openssl
  libeigen3-dev libceres-dev
  googletest libgtest-dev libbenchmark-dev
)

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
