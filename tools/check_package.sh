#!/usr/bin/env bash
# The ways a project takes wlx in, checked as a user would meet them (run by .ci/run after the
# README's test command has built build/):
#   1. the README's embedding recipe, verbatim (the sh block after "<!-- ci: embedding -->"):
#      install into a prefix, then build and run examples/controller against it;
#   2. the installed Python package imports from the prefix and solves;
#   3. add_subdirectory() of the source tree: only the runtime is configured, and the configure
#      finds neither GiNaC nor CLI11 nor nlohmann-json (not needed, so not looked for).
set -euo pipefail
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "-- the README's embedding recipe"
awk '/<!-- ci: embedding -->/ {marked = 1; next}
     marked && /^```sh/      {inside = 1; next}
     inside && /^```/        {exit}
     inside                  {print}' README.md > "$work/embedding.sh"
if ! grep -q 'cmake --install' "$work/embedding.sh"; then
  echo "README.md: no sh block after <!-- ci: embedding --> (or it does not install)" >&2
  exit 1
fi
cat "$work/embedding.sh"
bash -euo pipefail "$work/embedding.sh"

echo "-- the installed Python package"
if [ -d build/install/lib/python3/dist-packages/wlx ]; then
  PYTHONPATH="$PWD/build/install/lib/python3/dist-packages" /usr/bin/python3 -c '
import wlx
answer = wlx.model("excavator").ik({"z_C": 1.8})
assert answer["closure_residual"] <= 1e-12, answer
print("installed wlx:", wlx.__file__, "ik closure residual", answer["closure_residual"])'
else
  echo "no Python package installed (pybind11 or Python headers missing at configure time)" >&2
  exit 1
fi

echo "-- the installed wlx compiles a model file of its own (wlx --model-file)"
# The installed sources (share/wlx), not the source tree's: the plugin is built from what was
# installed. -O0: this checks the installed layout; tests/cli/test_model_file_plugin.cpp the rest.
sed 's/^model: .*/model: installed_check/' build/install/share/wlx/models/excavator.yaml > "$work/installed_check.yaml"
echo '{"z_C": 1.8}' | WLX_CACHE_DIR="$work/cache" WLX_PLUGIN_CXXFLAGS=-O0 \
  build/install/bin/wlx --model-file "$work/installed_check.yaml" fk --json > "$work/fk.json"
grep -q '"closure_residual"' "$work/fk.json"
grep -rq "share/wlx/cli/commands" "$work/cache"/installed_check-*/commands_unity.cpp || {
  echo "the plugin was not compiled from the installed sources" >&2; exit 1; }

echo "-- add_subdirectory(), runtime only"
cmake -S tests/package -B "$work/subdirectory" -G Ninja -DWLX_SOURCE_DIR="$PWD" > "$work/configure.log"
for needless in GINAC CLI11_DIR nlohmann_json_DIR yaml-cpp_DIR; do
  if grep -q "^$needless" "$work/subdirectory/CMakeCache.txt"; then
    echo "add_subdirectory(wlx) looked for $needless, which the runtime does not need" >&2
    exit 1
  fi
done
cmake --build "$work/subdirectory" --parallel "$(nproc)" > "$work/build.log" || { cat "$work/build.log" >&2; exit 1; }
"$work/subdirectory/uses_wlx"
