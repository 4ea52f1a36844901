#!/usr/bin/env bash
# Fuzzes the JSON/scenario input path, the IK on arbitrary numbers, the model-file reader and the
# command-line parser with libFuzzer (clang,
# ASan, UBSan) for SECONDS each (default 60). New interesting inputs stay in build-fuzz/; a
# crasher stops the run, is copied to tests/fuzz/regressions/<target>/ (commit it: every test
# run replays that folder) and the script exits 1.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
# CLN (GiNaC's numbers, in the model reader's target) keeps static memory until exit.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp}
for p in clang-14 libclang-rt-14-dev; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ -n "${missing[*]:-}" ]; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if [ ! -f build-fuzz/CMakeCache.txt ]; then
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 -DWLX_FUZZ=ON -DWLX_BUILD_PYTHON=OFF \
        -DWLX_BUILD_BENCHMARKS=OFF > /dev/null
fi
cmake --build build-fuzz --parallel "$(nproc)" --target fuzz_ik_numbers fuzz_json_input fuzz_model_file fuzz_command_line
status=0
for target in ik_numbers json_input model_file command_line; do
  work=build-fuzz/corpus-$target artifacts=build-fuzz/artifacts-$target
  mkdir -p "$work" "$artifacts" "tests/fuzz/regressions/$target"
  echo "fuzz_$target: ${seconds} s"
  if ! ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      "build-fuzz/tests/fuzz/fuzz_$target" -max_total_time="$seconds" -max_len=4096 -timeout=10 \
      -artifact_prefix="$artifacts/" "$work" "tests/fuzz/corpus/$target" "tests/fuzz/regressions/$target" \
      $([ "$target" = model_file ] && echo models) \
      > "build-fuzz/fuzz-$target.log" 2>&1; then
    status=1
    cp "$artifacts"/* "tests/fuzz/regressions/$target/" 2>/dev/null || true
    tail -40 "build-fuzz/fuzz-$target.log"
  fi
  grep -E "^#[0-9]+.*DONE|Done [0-9]+ runs" "build-fuzz/fuzz-$target.log" | tail -1 || true
done
exit $status
