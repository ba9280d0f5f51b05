#!/usr/bin/env bash
# raypack set-up: installs the Debian 12 packages raypack needs when any is missing
# (non-interactive, idempotent), then configures and builds a Release tree in ./build. The Python
# module is built for Debian's interpreter (/usr/bin/python3, which has python3-numpy and
# python3-pytest), whatever python3 comes first on PATH.
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
  libtinyobjloader-dev libtinygltf-dev libgmp-dev libxxhash-dev gnuplot-nox ccache
  libopenmpi-dev openmpi-bin
  pybind11-dev python3-dev python3-numpy python3-pytest
  python3-venv python3-setuptools python3-wheel
)

.ci/apt-install.sh setup "${packages[@]}"

jobs=${RAYPACK_JOBS:-2}
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DRAYPACK_MPI=ON -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build build -j"$jobs"
