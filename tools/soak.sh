#!/usr/bin/env bash
# A soak of the whole robot chain (issue 16; not in CI): `crunchhost --robot` for SECONDS inside
# crunch-virtual-robot (the ODE robot of test/scenes/hil_one_table.json behind umockdev USB and
# a pty Create), roaming and whisking the whole time. crunchhost's --json "status" line at every
# running-map write (every --map-every 10 s) gives resident memory, the USB ring's high water and
# drops, frames lost before the host, the Create watchdog's stops and the map writer's latency;
# this script keeps them in OUT/status.csv and charts them over time in OUT/soak.png with
# tools/soak_chart.py (Debian's python3-matplotlib). Uses the build in $CRUNCH_BUILD (default
# build/default; a copy lets the tree be rebuilt while a soak runs).
#   tools/soak.sh 3600 /tmp/soak     # the one-hour soak of docs/ROBOT.md
# Exit status: crunchhost's (0 a clean run), or 1 when the run's own checks fail (memory grew
# more than 10 % from the second tenth's median to the last tenth's, frames were lost, the ring
# dropped chunks, or the watchdog stopped the Create).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:?usage: tools/soak.sh SECONDS OUT_DIR}
out=${2:?usage: tools/soak.sh SECONDS OUT_DIR}
mkdir -p "$out"
build=${CRUNCH_BUILD:-build/default}  # the build whose binaries run
scene=test/scenes/hil_one_table.json
limit=$((seconds + 120))

echo "soak: ${seconds} s of crunchhost --robot in crunch-virtual-robot; output in $out" >&2
set +e
"$build/sim/tools/crunch-virtual-robot" --scene "$scene" --time-limit "$limit" -- \
  "$build/host/app/crunchhost" --robot --create '{create}' --start-x 0.3 --start-y 0.775 \
  --start-theta 0 --area-width 2 --area-depth 2 --duration "$seconds" --map-every 10 --json \
  --out "$out/run" >"$out/progress.jsonl" 2>"$out/stderr.log"
status=$?
set -e
echo "soak: crunchhost --robot inside the harness exited $status" >&2
/usr/bin/python3 tools/soak_chart.py "$out/progress.jsonl" "$out/run/report.json" "$out"
exit "$status"
