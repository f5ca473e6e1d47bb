#!/usr/bin/env bash
# Reproduces the charts of docs/RESULTS.md "Charts" (issue 6): builds crunchhost (Release, the
# default preset), runs two sweeps with the gaussian sensor model on the built-in arena and draws
# them with `crunchhost sweep-chart` into docs/img/results/{budget,noise}/.
#   (a) budget: noise realistic,noisy x schedule-steps 4,8,16 x sweeps 1,2 x working-memory 7,14
#       x seeds 1-3 (72 runs): accuracy against cost, the Pareto front, the paper's setting.
#   (b) noise: --noise-scale 0.5,1,2,3,5,8,12 (sigma_r 2.5 ... 60 mm) at the paper's setting x
#       seeds 1-5 (35 runs): accuracy against noise, where mapping fails.
#   (c) scale: bench/scale_bench, cost per proposal and memory against 1e2 .. 1e5 shapelets
#       (docs/RESULTS.md "Scale"; about 2 min), charts docs/img/results/scale*.png.
#   (d) blackboard snapshots at pose 120 of the default arena, cold and hot.
#   (e) models: --model paper,walls,rooms x --noise-scale 1,2,5 x schedule-steps 4,8,16 x seeds
#       1-3 (81 runs): accuracy against cost per object model and each model against noise
#       (docs/RESULTS.md "Object models"), docs/img/results/models/.
# The raw rows (sweep.csv/json) stay in build/results/; the charts, summary.csv and a copy of
# sweep.csv go to docs/img/results/. Usage: bash tools/make-results.sh [--jobs N]
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=$(nproc)
if [[ "${1:-}" == "--jobs" ]]; then JOBS="$2"; fi

cmake --preset default >/dev/null
cmake --build build/default --target crunchhost scale_bench
BIN=build/default/host/app/crunchhost
RAW=build/results
IMG=docs/img/results
mkdir -p "$RAW" "$IMG"

start=$(date +%s)
"$BIN" sweep --noise realistic,noisy --schedule-steps 4,8,16 --sweeps 1,2 --working-memory 7,14 \
    --seeds 3 --jobs "$JOBS" --out "$RAW/budget"
"$BIN" sweep-chart --in "$RAW/budget" --out "$IMG/budget"
cp "$RAW/budget/sweep.csv" "$IMG/budget/sweep.csv"

"$BIN" sweep --noise-scale 0.5,1,2,3,5,8,12 --seeds 5 --jobs "$JOBS" --out "$RAW/noise"
"$BIN" sweep-chart --in "$RAW/noise" --out "$IMG/noise"
cp "$RAW/noise/sweep.csv" "$IMG/noise/sweep.csv"
build/default/bench/scale_bench --chart "$IMG/scale"
# (d) blackboard snapshots (paper Figs. 3-4): pose 120 of the default arena, at the end of its
#     annealing and after its hottest temperature.
"$BIN" --sim --snapshot 120 --out "$RAW/snap_cold" >/dev/null
cp "$RAW/snap_cold/snapshot_120.png" "$IMG/snapshot_default_120.png"
"$BIN" --sim --snapshot 120 --snapshot-temperature 0 --out "$RAW/snap_hot" >/dev/null
cp "$RAW/snap_hot/snapshot_120.png" "$IMG/snapshot_default_120_hot.png"
"$BIN" sweep --model paper,walls,rooms --noise-scale 1,2,5 --schedule-steps 4,8,16 --seeds 3 \
    --jobs "$JOBS" --out "$RAW/models"
"$BIN" sweep-chart --in "$RAW/models" --out "$IMG/models"
cp "$RAW/models/sweep.csv" "$IMG/models/sweep.csv"
echo "make-results: sweeps, scale and charts in $(( $(date +%s) - start )) s; charts in $IMG/"
