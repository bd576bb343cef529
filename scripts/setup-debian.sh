#!/usr/bin/env bash
# Installs the Debian 12 packages Knitshade needs, and only those that are
# missing. Safe to run any number of times; does nothing when all is present.
#
#   scripts/setup-debian.sh            build + test dependencies
#   scripts/setup-debian.sh --minimal  only what the library, CLI, add-on and demo need (Blender too)
set -euo pipefail

build_pkgs=(
  build-essential cmake ninja-build pkg-config git
  libembree-dev libtbb-dev
  libopenimageio-dev openimageio-tools
  libopencolorio-dev
  libassimp-dev nlohmann-json3-dev
  python3 python3-dev python3-numpy pybind11-dev
  blender
)
test_pkgs=(
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev
  xvfb xauth
  python3-venv libvulkan1
)

want=("${build_pkgs[@]}")
if [[ "${1:-}" != "--minimal" ]]; then
  want+=("${test_pkgs[@]}")
fi

missing=()
for p in "${want[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#want[@]} Debian packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
$SUDO apt-get update
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
