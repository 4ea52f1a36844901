#!/usr/bin/env bash
# Each generated kernel of a built-in model under GCC and under clang, side by side in one process
# (bench/compilers/): their times and the ratio, for the issue of code that one compiler makes
# slower than the other; each compiler's fastest of 7 copies of the program (bench/compilers/main.cpp
# says why; its --variant also times other layouts, linked with bench/compilers/padding.cpp).
# Usage: tools/kernels_by_compiler.sh [MODEL] [FLAGS...]
# (default: wheeled_quadruped, -O3 as the build's Release; e.g. -O2 -DWLX_GEN_NO_MULTIVERSION).
set -euo pipefail
cd "$(dirname "$0")/.."
model=${1:-wheeled_quadruped}
shift || true
flags=("$@")
[ ${#flags[@]} -gt 0 ] || flags=(-O3)
[ -d "generated/$model/wlx/gen" ] || { echo "kernels_by_compiler: no generated/$model" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
common=(-std=c++20 -DNDEBUG "-DWLX_MODEL=$model" -I "generated/$model" -isystem /usr/include/eigen3 "${flags[@]}")
g++ "${common[@]}" -Wno-psabi -DKERNEL_NAMESPACE=by_gcc -c bench/compilers/kernels.cpp -o "$work/gcc.o" &
clang++-14 "${common[@]}" -DKERNEL_NAMESPACE=by_clang -c bench/compilers/kernels.cpp -o "$work/clang.o"
wait
clang++-14 -O2 bench/compilers/main.cpp "$work/gcc.o" "$work/clang.o" -o "$work/kernels"
echo "$model, ${flags[*]}:"
"$work/kernels" --copies 7
