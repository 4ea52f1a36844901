#!/usr/bin/env bash
# Writes what wlx-gen derives from every model file in the tree (the built-in models, the test
# models, the IK shapes; with and without --data-at-run-time, baked, and the --print-model and
# --describe texts) into OUT/<case>/: a refactoring of the generator compares two such folders
# (`diff -r`), which must be identical. Usage: tools/generator_outputs.sh WLX_GEN OUT
set -euo pipefail
gen=$(realpath "$1")
out=$2
cd "$(dirname "$0")/.."
rm -rf "$out" && mkdir -p "$out"
run() {  # case-name args...
  local name=$1; shift
  if ! "$gen" "$@" --out "$out/$name" --quiet > "$out/$name.stdout" 2> "$out/$name.stderr"; then echo "exit $?" >> "$out/$name.stderr"; fi
  "$gen" "$@" --print-model > "$out/$name.print-model" 2>&1 || true
  "$gen" "$@" --describe > "$out/$name.describe" 2>&1 || true
}
for f in models/*.yaml tests/models/*.yaml tests/ik_shapes/*.yaml; do
  case=$(echo "$f" | tr / _)
  run "$case" "$f"
  run "$case-runtime-data" "$f" --data-at-run-time
done
run models_excavator-baked models/excavator.yaml --bake-defaults
run big_wheeled tests/models/big_wheeled/big_wheeled.yaml
run big_wheeled-runtime-data tests/models/big_wheeled/big_wheeled.yaml --data-at-run-time
# Cases of the generator's own error messages: every fuzz regression and corpus model file.
for f in tests/fuzz/regressions/model_file/* tests/fuzz/corpus/model_file/*; do
  [ -f "$f" ] || continue
  case=err_$(basename "$f")
  "$gen" "$f" --out "$out/$case" --quiet > "$out/$case.stdout" 2> "$out/$case.stderr" || echo "exit $?" >> "$out/$case.stderr"
done
# URDFs (the fuzz corpus and regressions) with the wheeled quadruped's YAML file (its `urdf:` line
# left out, as --with wants).
inputs=$(mktemp -d) && trap 'rm -rf "$inputs"' EXIT
with=$inputs/with.yaml  # a fixed name: messages quote it
grep -v '^urdf:' models/wheeled_quadruped.yaml > "$with"
for f in models/wheeled_quadruped.urdf tests/fuzz/regressions/urdf/* tests/fuzz/corpus/urdf/*; do
  case=urdf_$(basename "$f" .urdf)
  cp "$f" "$inputs/$case.urdf"
  (cd "$inputs" && "$gen" "$case.urdf" --with with.yaml --print-model) > "$out/$case.print-model" 2>&1 || echo "exit $?" >> "$out/$case.print-model"
done
# Paths of the files given are in some messages: the same tree gives the same text.
echo "wrote $(find "$out" -type f | wc -l) files to $out"
