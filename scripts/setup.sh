#!/usr/bin/env bash
# Installs everything unjam needs to build, test and plot, from Debian packages.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev coinor-libclp-dev libmetis-dev libsuitesparse-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libbenchmark-dev
  libopenmpi-dev openmpi-bin
  clang libclang-rt-dev libomp-dev
  python3 python3-matplotlib python3-numpy
  python3-siconos lammps
  python3-dev pybind11-dev python3-pybind11 python3-pytest python3-vtk9 xvfb xauth
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "installing: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
