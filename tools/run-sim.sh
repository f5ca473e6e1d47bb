#!/usr/bin/env bash
# Installs dependencies, builds, and runs the main job: `crunchhost --sim` on the built-in
# default arena, writing out/map.png, out/map.json and out/report.json. Extra arguments are
# passed to crunchhost (e.g. --noise noisy --seed 7).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
cmake --preset default
cmake --build --preset default --target crunchhost
./build/default/host/app/crunchhost --sim --out out "$@"
