#!/usr/bin/env bash
# Without Microchip's tools, the XC16 toolchain file and the flashing tool must stop with a
# non-zero exit and say what to install. Skipped (exit 77) on a machine that has them.
set -uo pipefail
src="$1"
work="$2"
rm -rf "$work" && mkdir -p "$work"
if command -v xc16-gcc >/dev/null 2>&1 || command -v ipecmd.sh >/dev/null 2>&1 ||
   compgen -G "/opt/microchip/*" >/dev/null; then
  echo "Microchip tools are installed here; nothing to test"; exit 77
fi
fail=0
expect() {  # expect NAME RC OUTPUT PATTERN
  if [ "$2" -eq 0 ]; then echo "FAIL $1: exit 0"; fail=1; fi
  if ! grep -q -- "$4" <<<"$3"; then echo "FAIL $1: no '$4' in:"; echo "$3"; fail=1; fi
  [ "$fail" -eq 0 ] && echo "ok $1 (exit $2)"
}

out=$(env -u XC16_ROOT cmake -S "$src/firmware/hal/dspic33" -B "$work/xc16" \
      -DCMAKE_TOOLCHAIN_FILE="$src/firmware/cmake/xc16.cmake" 2>&1); rc=$?
expect "xc16.cmake without XC16" "$rc" "$out" 'Install "MPLAB XC16 Compiler"'

touch "$work/board.hex"
out=$(env -u IPECMD "$src/tools/flash-whisker-board" --hex "$work/board.hex" 2>&1); rc=$?
expect "flash without IPE" "$rc" "$out" "Install MPLAB X IDE for Linux"

out=$(env -u IPECMD "$src/tools/flash-whisker-board" --hex "$work/none.hex" 2>&1); rc=$?
expect "flash without a hex file" "$rc" "$out" "no hex file at $work/none.hex"
exit "$fail"
