#!/usr/bin/env bash
# Runs every libFuzzer target (docs/FUZZING.md) for SECONDS each, one after another, from a
# scratch copy of its committed seed corpus (test/fuzz/corpus/<name>/; the corpus the run grows
# stays in the scratch copy). Builds the `fuzz` preset first: needs Debian's clang and its
# libFuzzer runtime (apt install clang libclang-rt-14-dev; not part of CI's install). Prints
# each target's final libFuzzer statistics and a summary line per target:
#   tools/fuzz-all.sh 60            # a minute each
#   tools/fuzz-all.sh 1200 models   # only models_fuzz, 20 minutes
# A finding (a crash, a sanitizer report or a failed invariant) stops with libFuzzer's own exit
# status and leaves its input as crash-* in the scratch directory, which is printed.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:?usage: tools/fuzz-all.sh SECONDS [TARGET...]}
shift
# target name = corpus folder name
declare -A corpus=(
  [parsers_fuzz]="scene map" [bridge_stream_fuzz]=bridge [create_oi_fuzz]=""
  [recording_fuzz]=recording [models_fuzz]=models [metadata_fuzz]=metadata
  [sweep_rows_fuzz]=sweep)
targets=(parsers_fuzz bridge_stream_fuzz create_oi_fuzz recording_fuzz models_fuzz metadata_fuzz
         sweep_rows_fuzz)
if [ $# -gt 0 ]; then
  targets=()
  for t in "$@"; do targets+=("${t%_fuzz}_fuzz"); done
fi

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz

scratch=$(mktemp -d /tmp/crunch-fuzz.XXXXXX)
echo "fuzz-all: scratch directory $scratch"
summary=()
for t in "${targets[@]}"; do
  if [ -z "${corpus[$t]+x}" ]; then echo "fuzz-all: unknown target $t" >&2; exit 2; fi
  dir="$scratch/$t"
  mkdir -p "$dir/corpus"
  for c in ${corpus[$t]}; do cp test/fuzz/corpus/"$c"/* "$dir/corpus/"; done
  echo "== $t, ${seconds} s"
  (cd "$dir" && "$OLDPWD/build/fuzz/test/fuzz/$t" -max_total_time="$seconds" -print_final_stats=1 \
     -max_len=65536 -timeout=10 corpus 2>"$dir/log") || {
    status=$?
    tail -40 "$dir/log" >&2
    echo "fuzz-all: $t found something (exit $status): see $dir" >&2
    exit "$status"
  }
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$dir/log")
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$dir/log")
  summary+=("$(printf '%-20s %12s runs %8s/s  corpus %s' "$t" "$runs" "$rate" "$(ls "$dir/corpus" | wc -l)")")
done
printf 'fuzz-all: %s\n' "${summary[@]}"
