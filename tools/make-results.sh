#!/usr/bin/env bash
# Reproduces the charts of docs/RESULTS.md "Charts" (issue 6): builds crunchhost (Release, the
# default preset), runs two sweeps with the gaussian sensor model on the built-in arena and draws
# them with `crunchhost sweep-chart` into docs/img/results/{budget,noise}/.
#   (a) budget, the paper's model: noise realistic,noisy x schedule-steps 4,8,16 x sweeps 1,2 x working-memory 7,14
#       x seeds 1-3 (72 runs): accuracy against cost, the Pareto front, the paper's setting.
#   (b) noise, the paper's model: --noise-scale 0.5,1,2,3,5,8,12 (sigma_r 2.5 ... 60 mm) at the paper's setting x
#       seeds 1-5 (35 runs): accuracy against noise, where mapping fails.
#   (c) scale: bench/scale_bench, cost per proposal and memory against 1e2 .. 1e5 shapelets
#       (docs/RESULTS.md "Scale"; about 2 min), charts docs/img/results/scale*.png.
#   (d) blackboard snapshots at pose 120 of the default arena, cold and hot.
#   (e) models: --model paper,walls,rooms x noise realistic (5 mm, pi/32), x2 (10 mm) and the
#       paper's noisy (25 mm, pi/8) x schedule-steps 4,8,16 x seeds 1-5 (135 runs): accuracy
#       against cost per object model and each model against noise (docs/RESULTS.md "Object
#       models"), docs/img/results/models/.
#   (f) exploration (issue 14): sweep --explore grid,random,frontier,entropy,infogain x seeds 1-5
#       on the built-in arena and every mapping scene of test/scenes/ (not bad_*, hil_*,
#       physics_*), one sweep per scene with --travel-budget = 1.25 x the scene's grid trajectory
#       (the straight-line length of its pose list in order, at most EXPLORE_MAX_BUDGET m, default
#       300), drawn by sweep-chart (recall and F1 against metres driven, one chart per scene) into
#       docs/img/results/explore/ (docs/RESULTS.md "Exploration: recall against travel").
#       EXPLORE_POLICIES, EXPLORE_SEEDS, EXPLORE_SCENES (space-separated) and EXPLORE_MODEL
#       (default paper, as --sim; rooms for tables of any size) override the policies, the seed
#       count, the scenes and the object model; `bash tools/make-results.sh --only explore` runs
#       only this step.
# (f) keeps its curves.csv (5 MB for 135 runs) in build/results/explore/all/, not in docs/.
# The raw rows (sweep.csv/json) stay in build/results/; the charts, summary.csv and a copy of
# sweep.csv go to docs/img/results/. Usage: bash tools/make-results.sh [--jobs N] [--only explore|charts]
# (--only charts: (a)-(e) without the exploration step, a few minutes instead of hours.)
# (CRUNCHHOST_BIN=PATH: run that crunchhost and build nothing.)
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS=$(nproc)
ONLY=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --jobs) JOBS="$2"; shift 2 ;;
    --only) ONLY="$2"; shift 2 ;;
    *) echo "make-results: unknown argument $1 (--jobs N, --only explore|charts)" >&2; exit 2 ;;
  esac
done

[[ -n "${CRUNCHHOST_BIN:-}" ]] || cmake --preset default >/dev/null
[[ -n "${CRUNCHHOST_BIN:-}" ]] || cmake --build build/default --target crunchhost scale_bench
BIN=${CRUNCHHOST_BIN:-build/default/host/app/crunchhost}
RAW=build/results
IMG=docs/img/results
mkdir -p "$RAW" "$IMG"

# (f) exploration: recall and F1 against metres driven, every policy on every mapping scene.
explore_step() {
  local policies="${EXPLORE_POLICIES:-grid,random,frontier,entropy,infogain}"
  local seeds="${EXPLORE_SEEDS:-5}" max_budget="${EXPLORE_MAX_BUDGET:-300}"
  local scenes="${EXPLORE_SCENES:-}" model="${EXPLORE_MODEL:-paper}"
  if [[ -z "$scenes" ]]; then
    scenes="default"
    for f in test/scenes/*.json; do
      case "$(basename "$f")" in bad_*|hil_*|physics_*) continue ;; esac
      scenes="$scenes $f"
    done
  fi
  local raw="$RAW/explore" t0
  t0=$(date +%s)
  rm -rf "$raw"
  mkdir -p "$raw/all"
  for scene in $scenes; do
    local stem budget
    stem=$(basename "$scene" .json)
    # The scene's grid trajectory: its pose list (scene.h poseGrid: 0.3 m margin, x fastest;
    # the default arena's 10 x 10) in order, straight lines between positions.
    budget=$(python3 - "$scene" "$max_budget" <<'PY'
import json, math, sys
scene, cap = sys.argv[1], float(sys.argv[2])
if scene == "default":
    w, d, g = 4.0, 4.0, {"grid": [10, 10, 4]}
else:
    s = json.load(open(scene))
    w, d = s["arena"]["width"], s["arena"]["depth"]
    g = s.get("poses", {"grid": [10, 10, 4]})
def coord(i, n, extent):
    m = min(0.3, 0.5 * extent)
    return 0.5 * extent if n == 1 else m + (extent - 2 * m) * i / (n - 1)
if "grid" in g:
    nx, ny = g["grid"][0], g["grid"][1]
    pts = [(coord(ix, nx, w), coord(iy, ny, d)) for iy in range(ny) for ix in range(nx)]
else:
    pts = [(p[0], p[1]) for p in g["list"]]
length = sum(math.dist(a, b) for a, b in zip(pts, pts[1:]))
print("%.1f" % min(cap, 1.25 * length))
PY
)
    echo "make-results (f): $stem, travel budget $budget m"
    "$BIN" sweep --scene "$scene" --model "$model" --explore "$policies" \
        --travel-budget "$budget" --seeds "$seeds" --jobs "$JOBS" --out "$raw/$stem"
    if [[ ! -s "$raw/all/curves.csv" ]]; then
      cp "$raw/$stem/curves.csv" "$raw/all/curves.csv"
    else
      tail -n +2 "$raw/$stem/curves.csv" >> "$raw/all/curves.csv"
    fi
  done
  rm -rf "$IMG/explore"
  "$BIN" sweep-chart --in "$raw/all" --out "$IMG/explore"
  echo "make-results (f): exploration in $(( $(date +%s) - t0 )) s; charts in $IMG/explore/"
}

if [[ "$ONLY" == "explore" ]]; then
  explore_step
  exit 0
elif [[ -n "$ONLY" && "$ONLY" != "charts" ]]; then
  echo "make-results: --only takes 'explore' or 'charts'" >&2
  exit 2
fi

start=$(date +%s)
"$BIN" sweep --model paper --noise realistic,noisy --schedule-steps 4,8,16 --sweeps 1,2 --working-memory 7,14 \
    --seeds 3 --jobs "$JOBS" --out "$RAW/budget"
"$BIN" sweep-chart --in "$RAW/budget" --out "$IMG/budget"
cp "$RAW/budget/sweep.csv" "$IMG/budget/sweep.csv"

"$BIN" sweep --model paper --noise-scale 0.5,1,2,3,5,8,12 --seeds 5 --jobs "$JOBS" --out "$RAW/noise"
"$BIN" sweep-chart --in "$RAW/noise" --out "$IMG/noise"
cp "$RAW/noise/sweep.csv" "$IMG/noise/sweep.csv"
build/default/bench/scale_bench --chart "$IMG/scale"
# (d) blackboard snapshots (paper Figs. 3-4): pose 120 of the default arena, at the end of its
#     annealing and after its hottest temperature.
"$BIN" --sim --model paper --snapshot 120 --out "$RAW/snap_cold" >/dev/null
cp "$RAW/snap_cold/snapshot_120.png" "$IMG/snapshot_default_120.png"
"$BIN" --sim --model paper --snapshot 120 --snapshot-temperature 0 --out "$RAW/snap_hot" >/dev/null
cp "$RAW/snap_hot/snapshot_120.png" "$IMG/snapshot_default_120_hot.png"
"$BIN" sweep --model paper,walls,rooms --noise realistic,noisy --noise-scale 2 --schedule-steps 4,8,16 --seeds 5 \
    --jobs "$JOBS" --out "$RAW/models"
"$BIN" sweep-chart --in "$RAW/models" --out "$IMG/models"
cp "$RAW/models/sweep.csv" "$IMG/models/sweep.csv"
[[ "$ONLY" == "charts" ]] || explore_step
echo "make-results: sweeps, scale and charts in $(( $(date +%s) - start )) s; charts in $IMG/"
