#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite: the Release build's default
# ctest set (unit + integration + hil), then the unit tests again under AddressSanitizer and
# UBSan. ctest runs two tests at a time (the test presets' execution.jobs); the asan build
# builds only what the unit tests run (build preset target unit_tests). Each phase's wall time
# is printed at the end (docs/BENCHMARKS.md, "CI time").
set -euo pipefail
cd "$(dirname "$0")/.."

times=()
phase() {
  local name=$1 t0=$SECONDS
  shift
  "$@"
  times+=("$(printf '%-16s %5d s' "$name" $((SECONDS - t0)))")
}
unit_count() { ctest --test-dir "$1" -L unit -N | sed -n 's/^Total Tests: //p'; }

phase install-deps bash tools/install-deps.sh
phase configure cmake --preset default
phase build cmake --build --preset default
phase test ctest --preset default
phase asan-configure cmake --preset asan
phase asan-build cmake --build --preset asan
# The asan build is partial: every unit test the Release build has must be there too.
release_units=$(unit_count build/default) asan_units=$(unit_count build/asan)
if [ "$release_units" != "$asan_units" ]; then
  echo "run-tests: the asan build has $asan_units unit tests, the Release build $release_units:" \
       "add the missing executable to the unit_tests target (test/CMakeLists.txt)" >&2
  exit 1
fi
phase asan-test ctest --preset asan-unit
printf 'run-tests: %s\n' "${times[@]}"
