#!/usr/bin/env bash
# raypack set-up: installs the Debian 12 packages raypack needs when any is missing
# (non-interactive, idempotent), then configures and builds a Release tree in ./build.
# Usage: .ci/setup.sh            (from the repository root; prints what it does)
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake pkg-config
  libembree-dev libtbb-dev
  libxsimd-dev xtl-dev
  libopenimageio-dev openimageio-tools
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev
  libtinyobjloader-dev libtinygltf-dev gnuplot-nox
)

.ci/apt-install.sh setup "${packages[@]}"

jobs=${RAYPACK_JOBS:-2}
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$jobs"
