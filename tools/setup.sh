#!/usr/bin/env bash
# Installs every Debian package vsd-sumo needs (only those missing), then
# configures and builds it in ./build (Release). Safe to run repeatedly.
#
#   tools/setup.sh && build/vsd-sumo run scenarios/acc_lk.yaml        # the main job
#   tools/setup.sh && ctest --test-dir build --output-on-failure -j2  # the tests
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  # toolchain
  cmake g++ make pkg-config git
  # simulation: libsumo (libsumocpp + headers), netconvert, SUMO's data files and traci (tests)
  sumo sumo-tools
  # model: libtorch (CPU) with OpenBLAS instead of the reference BLAS (~10x faster products)
  libtorch-dev libopenblas0-pthread
  # distribution: MPI for run/export sweeps (optional at build time, installed so tests use it),
  # Gloo's headers for torch.distributed's c10d ProcessGroupGloo (data-parallel training)
  libopenmpi-dev openmpi-bin libgloo-dev
  # libraries
  libeigen3-dev libyaml-cpp-dev libhdf5-dev libdeflate-dev libcli11-dev libspdlog-dev libfmt-dev libmuparser-dev
  nlohmann-json3-dev libssl-dev libpugixml-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev libxml2-utils python3 python3-h5py python3-numpy python3-sklearn python3-pil chromium
)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# SUMO needs its data files (XML schemas, OpenDRIVE type maps).
export SUMO_HOME="${SUMO_HOME:-/usr/share/sumo}"

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
echo "setup: built build/vsd-sumo"
