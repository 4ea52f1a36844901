#!/usr/bin/env bash
# One clang tree with AddressSanitizer + UndefinedBehaviorSanitizer (and libFuzzer's coverage
# instrumentation, on all but the tests' own files: tests/CMakeLists.txt) that serves both the
# whole test suite and the fuzzers, so the sanitized objects are compiled once (.ci/run; issue
# "CI within 30 minutes").
#   tools/sanitizer_tree.sh test          configure, build the tests, run them (ctest)
#   tools/sanitizer_tree.sh fuzz SECONDS  configure, build the libFuzzer targets, fuzz each for SECONDS
# Not sanitized: the benchmarks, the viewer (emscripten's WebAssembly) and the Python module, which
# take no untrusted input beyond what the tests run through the command line; the KDL comparison
# and MuJoCo's check of the exported models (outside libraries' numbers, checked in the normal
# tree; the export itself is sanitized in the command-line tests); and of the built-in models all
# but the excavator: its runtime and commands (two wheels, eight actuators, a closure, wheel levers) and the
# test models built beside it (tests/models: a floating tripod on pinned feet with no wheels, an open
# arm, a one-wheeled leg of Newton limbs; tests/ik_shapes: every closed-form limb pattern) take
# every path of the generic runtime with every count of wheels the runtime distinguishes (0, 1,
# many); the walker's and the wheeled quadruped's runtimes are the same code on other numbers, each
# sanitized model costs three minutes of CI's CPU, and the normal tree tests them all.
# The excavator enters as a model file's path (models/excavator.yaml), so that CI builds a model
# from a file as users building from source do. The tree is ${WLX_SANITIZER_DIR:-build-sanitize}.
set -euo pipefail
cd "$(dirname "$0")/.."
what=${1:?usage: tools/sanitizer_tree.sh test | fuzz SECONDS}
tree=${WLX_SANITIZER_DIR:-build-sanitize}
missing=()
for p in clang-14 libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  apt_get=(apt-get); [ "$(id -u)" -eq 0 ] || apt_get=(sudo apt-get)
  "${apt_get[@]}" update -qq && DEBIAN_FRONTEND=noninteractive "${apt_get[@]}" install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if [ ! -f "$tree/CMakeCache.txt" ]; then
  # -O1 with line tables only: the sanitizers' reports keep file:line, and the big straight-line
  # generated functions compile in a fraction of the time full debug information takes.
  cmake -S . -B "$tree" -G Ninja -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_COMPILER=clang++-14 \
        -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -gline-tables-only -DNDEBUG" \
        -DWLX_SANITIZE=ON -DWLX_FUZZ=ON -DWLX_BUILD_BENCHMARKS=OFF -DWLX_BUILD_PYTHON=OFF -DWLX_BUILD_VIEWER=OFF \
        -DWLX_INSTALL=OFF -DWLX_USE_KDL=OFF "-DWLX_MODELS=models/excavator.yaml" > /dev/null
fi
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# CLN and GiNaC keep memory until exit (tools/lsan.supp). print_suppressions=0: the tests compare
# the exact standard error of the programs they run, which must not gain LeakSanitizer's summary.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp:print_suppressions=0}
fuzz_targets=(ik_numbers json_input model_file command_line report_file urdf)

case "$what" in
  test)
    cmake --build "$tree" --parallel "$(nproc)"
    # The excavator is given as a model file (-DWLX_MODELS takes paths): generated into the build
    # tree, the source tree's generated/ untouched (the normal tree's freshness test checks it).
    [ -f "$tree/generated-models/excavator/wlx/gen/all.hpp" ] || {
      echo "WLX_MODELS' model file was not generated into $tree/generated-models/" >&2; exit 1; }
    ctest --test-dir "$tree" --output-on-failure --parallel "$(nproc)"
    ;;
  fuzz)
    seconds=${2:-60}
    cmake --build "$tree" --parallel "$(nproc)" --target "${fuzz_targets[@]/#/fuzz_}"
    # Crashers stop the run and are copied to tests/fuzz/regressions/<target>/ (commit them:
    # every test run replays that folder); new interesting inputs stay in the tree. Each fuzzer is
    # one process on one core: as many run at once as there are cores (on CI's two, the five take
    # three rounds of SECONDS instead of five).
    fuzz_one() {
      local target=$1 work=$tree/corpus-$1 artifacts=$tree/artifacts-$1
      mkdir -p "$work" "$artifacts" "tests/fuzz/regressions/$target"
      local seeds=("tests/fuzz/corpus/$target" "tests/fuzz/regressions/$target")
      [ "$target" = model_file ] || [ "$target" = urdf ] && seeds+=(models)
      [ "$target" = report_file ] && seeds+=(scenarios/excavator)  # as the replay test (tests/CMakeLists.txt)
      ASAN_OPTIONS=detect_leaks=1 "$tree/tests/fuzz/fuzz_$target" -max_total_time="$seconds" -max_len=4096 \
          -timeout=10 -artifact_prefix="$artifacts/" "$work" "${seeds[@]}" > "$tree/fuzz-$target.log" 2>&1
    }
    status=0
    cores=$(nproc)
    for ((first = 0; first < ${#fuzz_targets[@]}; first += cores)); do
      round=("${fuzz_targets[@]:first:cores}")
      pids=()
      for target in "${round[@]}"; do
        echo "fuzz_$target: ${seconds} s"
        fuzz_one "$target" &
        pids+=($!)
      done
      for k in "${!round[@]}"; do
        target=${round[$k]}
        if ! wait "${pids[$k]}"; then
          status=1
          cp "$tree/artifacts-$target"/* "tests/fuzz/regressions/$target/" 2>/dev/null || true
          echo "fuzz_$target failed:"
          # The finding's stack first (a tail alone cut it off), then the input that caused it.
          grep -m1 -A 24 -E "ERROR: |runtime error: |==[0-9]+== ?ERROR" "$tree/fuzz-$target.log" || true
          echo "..."
          tail -6 "$tree/fuzz-$target.log"
        fi
        echo "fuzz_$target: $(grep -E "^#[0-9]+.*DONE|Done [0-9]+ runs" "$tree/fuzz-$target.log" | tail -1 || true)"
      done
    done
    exit $status
    ;;
  *) echo "usage: tools/sanitizer_tree.sh test | fuzz SECONDS" >&2; exit 2 ;;
esac
