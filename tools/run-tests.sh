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
# The executables the Release build's unit tests run, as paths relative to build/default.
unit_executables() {
  ctest --test-dir build/default -L unit -N -V | sed -n "s|^.*Test command: $PWD/build/default/\([^ ]*\).*|\1|p" |
    sort -u
}

phase install-deps bash tools/install-deps.sh
phase configure cmake --preset default
phase build cmake --build --preset default
phase test ctest --preset default
phase asan-configure cmake --preset asan
phase asan-build cmake --build --preset asan
# The asan build is partial: every executable the unit tests run must be there too (a test
# executable missing from unit_tests would only show as an unlabelled *_NOT_BUILT test, which the
# unit filter drops silently).
for exe in $(unit_executables); do
  if [ ! -x "build/asan/$exe" ]; then
    echo "run-tests: build/asan/$exe missing: add it to the unit_tests target (test/CMakeLists.txt)" >&2
    exit 1
  fi
done
phase asan-test ctest --preset asan-unit
printf 'run-tests: %s\n' "${times[@]}"
