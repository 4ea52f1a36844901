#!/usr/bin/env bash
# Regenerates every figure README.md quotes, in its "<!-- figures: NAME -->" sections: the
# integrator table (NH-4: steps, evaluations, errors), the benchmark table (every row
# `wlx_bench --json` reports, with the machine and the date), the generation table (per model,
# wlx_bench_generator's BM_generate_everything/<model> and tools/header_compile_times.py's -O2
# compile time of each generated header) and the controller's step times.
# The deterministic figures are checked by the test docs_figures; timings only change here.
# Run it on a quiet machine after a change that moves the numbers, then commit README.md.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${WLX_BUILD_DIR:-build}
[ -f "$build/CMakeCache.txt" ] || bash tools/setup.sh
cmake --build "$build" --target wlx wlx_bench wlx_bench_generator
# The controller of the README's embedding recipe, built by that recipe (as tools/check_package.sh
# runs it) when it is missing or older than the build.
if [ ! -x "$build/controller/controller" ] || [ "$build/wlx" -nt "$build/controller/controller" ]; then
  recipe=$(mktemp)
  trap 'rm -f "$recipe"' EXIT
  awk '/<!-- ci: embedding -->/ {marked = 1; next}
       marked && /^```sh/      {inside = 1; next}
       inside && /^```/        {exit}
       inside && !/^build\/controller\/controller$/ {print}' README.md > "$recipe"
  sed -i "s#\bbuild/#$build/#g" "$recipe"
  bash -euo pipefail "$recipe" > /dev/null
fi
python3 tools/docs_contract.py figures --write --build "$build"
git --no-pager diff --stat -- README.md || true
