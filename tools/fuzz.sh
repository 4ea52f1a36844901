#!/usr/bin/env bash
# Fuzzes the JSON/scenario input path, the IK on arbitrary numbers, the model-file and URDF readers and the
# command-line parser with libFuzzer (clang, ASan, UBSan) for SECONDS each (default 60), in the
# sanitized tree the tests also use (tools/sanitizer_tree.sh). A crasher stops the run, is copied
# to tests/fuzz/regressions/<target>/ (commit it) and the script exits 1.
exec "$(dirname "$0")/sanitizer_tree.sh" fuzz "${1:-60}"
