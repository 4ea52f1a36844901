#!/usr/bin/env bash
# The ways a project takes wlx in, checked as a user would meet them (run by .ci/run after the
# README's test command has built build/):
#   1. the README's embedding recipe, verbatim (the sh block after "<!-- ci: embedding -->"):
#      install into a prefix, then build and run examples/controller against it;
#   2. the installed Python package imports from the prefix and solves;
#   3. the installed wlx compiles a model file of its own (--model-file), for the CLI and Python;
#   4. wlx_generate(... PYTHON) in a project of one's own, and its regeneration on an edit;
#   5. add_subdirectory() of the source tree: only the runtime is configured, and the configure
#      finds neither GiNaC nor CLI11 nor nlohmann-json (not needed, so not looked for).
set -euo pipefail
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Each check's wall time, printed as it ends and, when all passed, together at the end (.ci/run's
# header says where the phase's time goes).
timings=()
check_started=0
check_name=""
check() {
  local now
  now=$(date +%s)
  if [ -n "$check_name" ]; then
    timings+=("$(printf '%5d s  %s' $((now - check_started)) "$check_name")")
    echo "${timings[-1]}"
  fi
  check_started=$now
  check_name=$1
  [ -n "$check_name" ] && echo "-- $check_name"
  return 0
}

check "the README's embedding recipe"
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

check "the installed Python package"
if [ -d build/install/lib/python3/dist-packages/wlx ]; then
  PYTHONPATH="$PWD/build/install/lib/python3/dist-packages" /usr/bin/python3 -c '
import wlx
answer = wlx.model("excavator").ik({"z_C": 1.8})
assert answer["closure_residual"] <= 1e-12, answer
assert callable(wlx.sweep)  # the sweep engine (python/wlx/_sweep.py) was installed with it
print("installed wlx:", wlx.__file__, "ik closure residual", answer["closure_residual"])'
  # wlx sweep: the installed wlx runs the installed package (python3 -m wlx sweep).
  printf '%s\n' 'parameters: {list: [{legD: 1.5}, {legD: 1.6}]}' 'runs: [NH-1]' 'metrics: [peak_cond_J_beta]' > "$work/sweep.yaml"
  env -u PYTHONPATH build/install/bin/wlx sweep "$work/sweep.yaml" --workers 1 --out "$work/sweep"
  grep -q '^1,1.6,NH-1,true,' "$work/sweep/results.csv"
else
  echo "no Python package installed (pybind11 or Python headers missing at configure time)" >&2
  exit 1
fi

check "the installed wlx compiles a model file of its own (wlx --model-file)"
# The installed sources (share/wlx), not the source tree's: the plugin is built from what was
# installed. -O0: this checks the installed layout; tests/cli/test_model_file_plugin.cpp the rest.
sed 's/^model: .*/model: installed_check/' build/install/share/wlx/models/excavator.yaml > "$work/installed_check.yaml"
echo '{"z_C": 1.8}' | WLX_CACHE_DIR="$work/cache" WLX_PLUGIN_CXXFLAGS=-O0 \
  build/install/bin/wlx --model-file "$work/installed_check.yaml" fk --json > "$work/fk.json"
grep -q '"closure_residual"' "$work/fk.json"
grep -rq "share/wlx/cli/commands" "$work/cache"/installed_check-*/commands_unity.cpp || {
  echo "the plugin was not compiled from the installed sources" >&2; exit 1; }
# Built by Clang, wlx installs its plugins' precompiled headers (the -O0 one, the commands', with its
# code: plugin_prelude-O0.a), the installed one was accepted (its check compile's log is empty:
# cli/shell/model_plugin.cpp), and the plugin linked its code (the plugin loaded: fk answered).
if [ -f build/plugin_prelude/plugin_prelude-O0.pch ]; then
  for f in plugin_prelude-O0.pch plugin_prelude-O0.a; do
    [ -f "build/install/share/wlx/precompiled/$f" ] || {
      echo "the plugins' precompiled headers were not installed: $f is missing" >&2; exit 1; }
  done
  log=$(echo "$work/cache"/installed_check-*/precompiled-O0.log)
  [ -f "$log" ] && [ ! -s "$log" ] || {
    echo "the installed precompiled header was not used: $(cat "$log" 2>/dev/null)" >&2; exit 1; }
fi
# The installed Python package loads the same file from the same cache entry (one plugin serves
# `wlx --model-file` and wlx.load), without compiling again.
WLX_CACHE_DIR="$work/cache" WLX_PLUGIN_CXXFLAGS=-O0 PYTHONPATH="$PWD/build/install/lib/python3/dist-packages" \
  /usr/bin/python3 -c '
import json, sys, time, wlx
start = time.monotonic()
robot = wlx.load(sys.argv[1])
seconds = time.monotonic() - start
answer = robot.ik({"z_C": 1.8})
cli = json.load(open(sys.argv[2]))
assert robot.name == "installed_check" and answer["closure_residual"] <= 1e-12, answer
assert abs(answer["s"][robot.coordinates.index("psi_l2")] - cli["coordinates"]["psi_l2"]) <= 1e-12, (answer, cli)
assert seconds < 5, f"wlx.load compiled again ({seconds:.1f} s): the cache entry was not shared"
print(f"installed wlx.load: {robot!r} from the cache in {seconds * 1000:.0f} ms")' "$work/installed_check.yaml" "$work/fk.json" 2> "$work/load.err"
if grep -q "compiling" "$work/load.err"; then cat "$work/load.err" >&2; echo "wlx.load compiled again" >&2; exit 1; fi
# The same model file through the installed wlx's other commands (issue 25: verify, simulate,
# report and viewer with the installed package only), with a run of the user's own.
mkdir -p "$work/runs"
echo '{"model": "installed_check", "description": "forward", "rates": {"x_C": 0.5}, "dependent": ["y_C", "yaw"], "duration": 0.2}' \
  > "$work/runs/forward.json"
installed_wlx() { WLX_CACHE_DIR="$work/cache" WLX_PLUGIN_CXXFLAGS=-O0 WLX_PLUGIN_EMCCFLAGS=-O0 build/install/bin/wlx --model-file "$work/installed_check.yaml" "$@"; }
installed_wlx verify ik --sweep IK-L3 --out "$work/verify" > /dev/null
installed_wlx --scenarios "$work/runs" simulate forward --out "$work/simulate" > /dev/null
[ "$(wc -l < "$work/simulate/trajectory.csv")" -eq 202 ] || { echo "installed simulate: not 201 samples" >&2; exit 1; }
installed_wlx --scenarios "$work/runs" report --quick --out "$work/report" > /dev/null 2> "$work/report.err" || {
  cat "$work/report.err" >&2; exit 1; }
grep -q "forward" "$work/report/index.html"
if [ -d build/install/share/wlx/viewer ]; then
  installed_wlx --scenarios "$work/runs" viewer forward --out "$work/viewer" > /dev/null
  [ -f "$work/viewer/wasm/wlx_installed_check.js" ] && [ -f "$work/viewer/runs/forward.js" ] || {
    echo "installed viewer: the model file's module or its run is missing" >&2; exit 1; }
  if compgen -G "$work/cache/installed_check-*/viewer.build-*" > /dev/null; then
    echo "a viewer build folder was left behind" >&2; exit 1; fi
fi
echo "installed wlx --model-file: verify ik, simulate, report and viewer of a model file it had not seen"

check "wlx_generate(... PYTHON): the Python package built for a model in a project of one's own"
# -O0: this checks the package's layout and the module's API; its numbers are the CLI's. Clang,
# as the build's: GCC took twice as long here (39 s of CI's wall time), and the recipe above
# builds the runtime with GCC already (the check: 39 s with GCC, 25 s with clang).
sed 's/^model: .*/model: python_check/' "$work/installed_check.yaml" > "$work/python_check.yaml"
cmake -S tests/package/python -B "$work/python" -G Ninja -DCMAKE_PREFIX_PATH="$PWD/build/install" -DCMAKE_CXX_FLAGS=-O0 \
      -DCMAKE_CXX_COMPILER=clang++-14 -DMODEL="$work/python_check.yaml" > "$work/python-configure.log" || { cat "$work/python-configure.log" >&2; exit 1; }
cmake --build "$work/python" --parallel "$(nproc)" > "$work/python-build.log" || { tail -50 "$work/python-build.log" >&2; exit 1; }
PYTHONPATH="$work/python/wlx_python/my_robot" /usr/bin/python3 -c '
import json, sys, wlx
assert wlx.models() == ["python_check"], wlx.models()
robot = wlx.model("python_check")
answer = robot.ik({"z_C": 1.8})
cli = json.load(open(sys.argv[1]))
assert abs(answer["s"][robot.coordinates.index("psi_l2")] - cli["coordinates"]["psi_l2"]) <= 1e-12, (answer, cli)
run = robot.simulate({"model": "python_check", "rates": {"x_C": 0.5}, "dependent": ["y_C", "yaw"], "duration": 0.2})
assert run["complete"] and len(run["t"]) == 201, run["stopped"]
try:
    robot.simulate(sys.argv[2])
except wlx.Error as e:
    assert "the scenario is for model \x27installed_check\x27, not for \x27python_check\x27" in str(e), str(e)
else:
    raise AssertionError("a run of another model ran")
print("wlx_generate(PYTHON): wlx.model(\"python_check\") from", wlx.__file__)' "$work/fk.json" "$work/runs/forward.json"

# wlx-gen tells the build what the model was read from (a depfile): built, nothing is dirty; an
# edit of the model file makes its generation dirty, without CMake having read the file.
if ! ninja -C "$work/python" -n | grep -q "no work to do"; then
  ninja -C "$work/python" -n -d explain >&2; echo "wlx_generate: a build after a build is not empty" >&2; exit 1; fi
touch "$work/python_check.yaml"
ninja -C "$work/python" -n my_robot_wlx_gen | grep -q "wlx-gen: .*python_check.yaml" || {
  echo "wlx_generate: an edit of the model file does not run wlx-gen" >&2; exit 1; }
# The model's name is NAME, else the file's name: a file named otherwise than its model is an
# error of the build that names both (CMake never reads the model file).
cp "$work/python_check.yaml" "$work/renamed.yaml"
cmake -S tests/package/python -B "$work/renamed" -G Ninja -DCMAKE_PREFIX_PATH="$PWD/build/install" -DMODEL="$work/renamed.yaml" \
      > "$work/renamed-configure.log" || { cat "$work/renamed-configure.log" >&2; exit 1; }
if cmake --build "$work/renamed" --target my_robot_wlx_gen > "$work/renamed-build.log" 2>&1 ||
   ! grep -q "renamed.yaml: \`model: python_check\`, where the build expects the model 'renamed' (wlx_generate's NAME" \
     "$work/renamed-build.log"; then
  cat "$work/renamed-build.log" >&2; echo "wlx_generate: a model file named otherwise than its model was not refused" >&2; exit 1
fi
echo "wlx_generate: regenerates on an edit of the model file (wlx-gen's depfile); a file named otherwise than its model is refused"

check "add_subdirectory(), runtime only"
# -O0: this checks what add_subdirectory() configures and that it builds and links; the runtime's
# optimised build is the embedding recipe's above (GCC at -O3 twice cost CI a minute of CPU). With
# clang, whose default language (C++14) is older than the runtime's headers need: the wlx targets
# must ask for C++17 themselves (a project that names no standard). GCC compiled this in 46 s of
# wall time at -O0 (the runtime's unity alone 34 s), clang in 19 s.
cmake -S tests/package -B "$work/subdirectory" -G Ninja -DWLX_SOURCE_DIR="$PWD" -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS=-O0 \
      -DCMAKE_CXX_COMPILER=clang++-14 \
      > "$work/configure.log" 2>&1 || { cat "$work/configure.log" >&2; exit 1; }
for needless in GINAC CLI11_DIR nlohmann_json_DIR yaml-cpp_DIR; do
  if grep -q "^$needless" "$work/subdirectory/CMakeCache.txt"; then
    echo "add_subdirectory(wlx) looked for $needless, which the runtime does not need" >&2
    exit 1
  fi
done
cmake --build "$work/subdirectory" --parallel "$(nproc)" > "$work/build.log" || { cat "$work/build.log" >&2; exit 1; }
"$work/subdirectory/uses_wlx"
check ""
printf '%s\n' "${timings[@]}"
