#!/usr/bin/env bash
# Installs every build and test dependency of solo from Debian 12 packages.
# Idempotent: packages already present are not reinstalled, and apt is not
# touched at all when nothing is missing. Runs as root, or through sudo.
# `tools/setup.sh --fuzz` adds the compiler and runtime of the fuzz preset.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libcgal-dev libgmp-dev libmpfr-dev
  libopenmesh-dev
  libeigen3-dev
  libceres-dev
  libembree-dev
  libopencv-dev
  libopenimageio-dev openimageio-tools
  libtiff-dev
  libgtest-dev libgmock-dev
  libbenchmark-dev
  libtbb-dev
  libcli11-dev
  nlohmann-json3-dev
  gnuplot-nox
  pybind11-dev python3-dev python3-numpy python3-pytest
)
if [ "${1:-}" = "--fuzz" ]; then
  packages+=(clang libclang-rt-14-dev)
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

as_root=()
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then as_root=(sudo); else
    echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; fi
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
"${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
