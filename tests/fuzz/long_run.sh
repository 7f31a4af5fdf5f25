#!/usr/bin/env bash
# A long fuzzing run of every mesh reader and the config reader (docs/robustness.md), one target
# after the other, one process each (the machine has 2 cores):
#   bash tests/fuzz/long_run.sh [LIBFUZZER_FLAGS...]      default: -runs=2200000 per target
#   bash tests/fuzz/long_run.sh -max_total_time=3600      an hour per target
# Needs the fuzz build (cmake --preset fuzz && cmake --build --preset fuzz). The corpus grows in
# build-fuzz/long/corpus/<format> from run to run; findings land in build-fuzz/long/findings/.
# Prints each target's executions (libFuzzer's own count) and the total; exits 1 if any target
# found something or was interrupted.
set -uo pipefail
cd "$(dirname "$0")/../.."
BUILD=${PALOVERDE_FUZZ_BUILD:-build-fuzz}
FORMATS=${PALOVERDE_FUZZ_FORMATS:-"vtk vtu gmsh medit tetgen config"}
flags=("$@")
[ ${#flags[@]} -eq 0 ] && flags=(-runs=2200000)
out="$BUILD/long"
total=0
failed=0
for format in $FORMATS; do
  mkdir -p "$out/corpus/$format" "$out/findings/$format"
  log="$out/$format.log"
  inputs=("$out/corpus/$format" "tests/fuzz/seeds/$format")
  if [ "$format" = config ]; then inputs+=("$BUILD/tests/fuzz/example_configs")
  else inputs+=("$BUILD/tests/fuzz/corpus/$format"); fi
  [ -d "tests/fuzz/regressions/$format" ] && inputs+=("tests/fuzz/regressions/$format")
  rm -rf "$out/scratch"
  PALOVERDE_FUZZ_SCRATCH="$out/scratch" \
    "$BUILD/bin/fuzz_$format" "${flags[@]}" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
    -dict="tests/fuzz/dictionaries/$format.dict" -artifact_prefix="$out/findings/$format/" \
    -print_final_stats=1 "${inputs[@]}" >"$log" 2>&1
  status=$?
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
  if [ -z "$runs" ]; then  # in case it ended before printing its final statistics
    runs=$(grep -oE '^#[0-9]+' "$log" | tail -1 | tr -d '#' || true)
  fi
  runs=${runs:-0}
  total=$((total + runs))
  if [ $status -eq 72 ]; then  # libFuzzer's code for SIGINT / SIGTERM
    failed=1
    echo "fuzz_$format: interrupted after $runs inputs, nothing found until then"
  elif [ $status -ne 0 ]; then
    failed=1
    echo "fuzz_$format: FOUND A PROBLEM after $runs inputs (exit $status); see $log and $out/findings/$format/"
  else
    echo "fuzz_$format: $runs inputs, nothing found"
  fi
done
echo "total: $total inputs"
exit $failed
