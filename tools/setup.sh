#!/usr/bin/env bash
# Installs the Debian packages wlx needs (only those missing), then configures and builds.
# Idempotent: a second run installs nothing and rebuilds only what changed.
#   tools/setup.sh --main   what the README's main job (`wlx report`) needs, and no more: the
#                           base packages, then wlx and wlx-gen with the default model (excavator)
#   tools/setup.sh          everything: every package, every built-in model, Python, the viewer,
#                           the tests, the benchmarks (the README's test command)
# The two share one build tree and never compile a file twice: the full setup adds the other
# models, and reconfigures once when packages were installed after the tree was configured, so
# that CMake finds them (the viewer, Python, KDL).
set -euo pipefail
cd "$(dirname "$0")/.."
mode=full
case "${1:-}" in
  --main) mode=main ;;
  "") ;;
  *) echo "usage: tools/setup.sh [--main]" >&2; exit 2 ;;
esac

# What building wlx and wlx-gen and writing the report need.
packages=(cmake g++ clang-14 ninja-build pkg-config libginac-dev libeigen3-dev libfmt-dev doctest-dev
          libcli11-dev nlohmann-json3-dev libyaml-cpp-dev libbenchmark-dev gnuplot-nox fonts-dejavu-core
          liburdfdom-dev    # URDF import in wlx-gen (optional in CMake; a built-in model is a URDF)
          libmujoco-dev)    # MuJoCo 2.2.2: the report's "In a physics engine", the check of `wlx export mjcf` (optional in CMake)
if [ "$mode" = full ]; then
  packages+=(python3-dev pybind11-dev python3-numpy python3-pytest python3-matplotlib
             python3-yaml python3-dask python3-distributed   # wlx sweep: spec files, and Dask for the runs
             liborocos-kdl-dev)  # Orocos KDL: the peer in wlx_bench and the KDL test (optional in CMake)
  # The 3D viewer (viewer/, CMake option WLX_BUILD_VIEWER): emscripten compiles the model's WebAssembly,
  # node and npm bundle the page (`npm ci` from viewer/package-lock.json runs inside the build, into
  # the build tree, only when the lock file changes), chromium runs its browser test. A gigabyte
  # unpacked: the main job does without (its report says the viewer is not built, and why).
  packages+=(emscripten chromium)
  # node and npm may come from elsewhere (NodeSource's nodejs carries npm): Debian's only if absent.
  command -v node >/dev/null || packages+=(nodejs)
  command -v npm >/dev/null || packages+=(npm)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
build=${WLX_BUILD_DIR:-build}
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  apt_get=(apt-get); [ "$(id -u)" -eq 0 ] || apt_get=(sudo apt-get)
  "${apt_get[@]}" update -qq
  DEBIAN_FRONTEND=noninteractive "${apt_get[@]}" install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  # A tree configured before these packages were there: configured again below, so that CMake finds them.
  [ -f "$build/CMakeCache.txt" ] && touch "$build/.wlx-reconfigure"
fi

configure=()
run_configure=false
if [ ! -f "$build/CMakeCache.txt" ]; then
  run_configure=true
  # clang compiles this tree in 60% of GCC's time (2 cores: 304 s against 511 s of wall time),
  # most of it Eigen's fixed-size templates; GCC still compiles the generated headers (the strict
  # C++17 test) and the runtime of the embedding check (tools/check_package.sh). CXX chooses another.
  compiler=()
  [ -z "${CXX:-}" ] && command -v clang++-14 >/dev/null && compiler=(-DCMAKE_CXX_COMPILER=clang++-14)
  configure=(-G Ninja -DCMAKE_BUILD_TYPE=Release "${compiler[@]}")
  # The main job: the default model only (the full setup adds the others to the same tree).
  if [ "$mode" = main ]; then
    configure+=(-DWLX_MODELS=excavator)
    mkdir -p "$build" && touch "$build/.wlx-main-only"
  fi
elif [ "$mode" = full ] && [ -f "$build/.wlx-main-only" ]; then
  run_configure=true
  configure=(-UWLX_MODELS)  # back to every built-in model
elif [ -f "$build/.wlx-reconfigure" ]; then
  run_configure=true  # CMake looks again for what it did not find
fi
if $run_configure; then
  cmake -S . -B "$build" "${configure[@]}"
  rm -f "$build/.wlx-reconfigure"
  [ "$mode" = full ] && rm -f "$build/.wlx-main-only"
fi
if [ "$mode" = main ]; then
  cmake --build "$build" --parallel "$(nproc)" --target wlx wlx-gen
else
  cmake --build "$build" --parallel "$(nproc)"
fi
