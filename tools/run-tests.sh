#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite: the Release build's default
# ctest set (unit + integration), then the unit tests again under AddressSanitizer and UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake --preset default
cmake --build --preset default
ctest --preset default
cmake --preset asan
cmake --build --preset asan
ctest --preset asan-unit
