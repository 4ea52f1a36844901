#!/usr/bin/env bash
# Installs the Debian packages wlx needs (only those missing), then configures and builds.
# Idempotent: a second run installs nothing and rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(cmake g++ clang-14 ninja-build pkg-config libginac-dev libeigen3-dev libfmt-dev doctest-dev
          libcli11-dev nlohmann-json3-dev libyaml-cpp-dev libbenchmark-dev gnuplot-nox fonts-dejavu-core
          python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib
          python3-yaml python3-dask python3-distributed   # wlx sweep: spec files, and Dask for the runs
          liborocos-kdl-dev   # Orocos KDL: the peer in wlx_bench and the KDL test (optional in CMake)
          liburdfdom-dev)     # URDF import in wlx-gen (optional in CMake)
# The 3D viewer (viewer/, CMake option WLX_BUILD_VIEWER): emscripten compiles the model's WebAssembly,
# node and npm bundle the page (`npm ci` from viewer/package-lock.json runs inside the build, into
# the build tree, only when the lock file changes), chromium runs its browser test.
packages+=(emscripten chromium)
# node and npm may come from elsewhere (NodeSource's nodejs carries npm): Debian's only if absent.
command -v node >/dev/null || packages+=(nodejs)
command -v npm >/dev/null || packages+=(npm)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  apt_get=(apt-get); [ "$(id -u)" -eq 0 ] || apt_get=(sudo apt-get)
  "${apt_get[@]}" update -qq
  DEBIAN_FRONTEND=noninteractive "${apt_get[@]}" install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

build=${WLX_BUILD_DIR:-build}
if [ ! -f "$build/CMakeCache.txt" ]; then
  # clang compiles this tree in 60% of GCC's time (2 cores: 304 s against 511 s of wall time),
  # most of it Eigen's fixed-size templates; GCC still compiles the generated headers (the strict
  # C++17 test) and the runtime of the embedding check (tools/check_package.sh). CXX chooses another.
  compiler=()
  [ -z "${CXX:-}" ] && command -v clang++-14 >/dev/null && compiler=(-DCMAKE_CXX_COMPILER=clang++-14)
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${compiler[@]}"
fi
cmake --build "$build" --parallel "$(nproc)"
