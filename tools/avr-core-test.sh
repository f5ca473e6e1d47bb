#!/usr/bin/env bash
# The firmware core on a 16-bit-int CPU: builds firmware/core + the host HAL + the plain-C test
# suite (test/firmware) with avr-gcc for an ATmega1284P (16 KB RAM, like the dsPIC33FJ128MC802)
# with warnings as errors, runs it under simavr, and checks the suite's closing line.
#
#   tools/avr-core-test.sh [OUT_DIR]      (default: build/avr-core)
#
# Exit: 0 if the suite printed "N passed, 0 failed" with N > 0; 1 on a compile error, a failed
# check, a crash or a hang (simavr itself exits 0 whatever happens, hence the parsing and the
# timeout); 77 (ctest SKIP) when avr-gcc is not installed. Prints the pass line, the ISR cycle
# count the suite measured, and avr-size of the core's objects.
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
OUT="${1:-$ROOT/build/avr-core}"
MCU=atmega1284p
F_CPU=16000000

if ! command -v avr-gcc >/dev/null 2>&1; then
  echo "fw_core_avr: SKIPPED: avr-gcc not found; install Debian gcc-avr avr-libc simavr" \
       "(tools/install-deps.sh does)"
  exit 77
fi
for tool in simavr avr-size; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "fw_core_avr: FAILED: avr-gcc is installed but $tool is not; install Debian simavr" \
         "and binutils-avr (tools/install-deps.sh)" >&2
    exit 1
  fi
done

CORE_SRCS=(error mlx90333 bridge_frame ring sampler board)
CFLAGS=(-mmcu="$MCU" -DF_CPU="${F_CPU}UL" -std=c99 -Os -g -Wall -Wextra -Wconversion -Werror
        -ffunction-sections -fdata-sections
        -I"$ROOT/firmware/core/include" -I"$ROOT/firmware/hal/host")

rm -rf "$OUT"
mkdir -p "$OUT"
core_objs=()
for s in "${CORE_SRCS[@]}"; do
  avr-gcc "${CFLAGS[@]}" -c "$ROOT/firmware/core/src/$s.c" -o "$OUT/$s.o"
  core_objs+=("$OUT/$s.o")
done
avr-gcc "${CFLAGS[@]}" -c "$ROOT/firmware/hal/host/hal_host.c" -o "$OUT/hal_host.o"
avr-gcc "${CFLAGS[@]}" -c "$ROOT/test/firmware/core_test.c" -o "$OUT/core_test.o"
avr-gcc -mmcu="$MCU" -Wl,--gc-sections "${core_objs[@]}" "$OUT/hal_host.o" "$OUT/core_test.o" \
  -o "$OUT/fw_core_test.elf"

# Run. UART0 output is printed by simavr (green, newline shown as '.'); strip the colour codes.
set +e
timeout 120 simavr -m "$MCU" -f "$F_CPU" "$OUT/fw_core_test.elf" >"$OUT/simavr.log" 2>&1
sim_rc=$?
set -e
sed -e 's/\x1b\[[0-9;]*m//g' "$OUT/simavr.log" >"$OUT/console.log"
grep -v -E '^(Loaded|$)' "$OUT/console.log" | grep -v -E '[0-9]+ passed, [0-9]+ failed' || true
if [ "$sim_rc" -eq 124 ]; then
  echo "fw_core_avr: FAILED: simavr still running after 120 s (a hang in the suite?)" >&2
  exit 1
fi

line="$(grep -o -E '[0-9]+ passed, [0-9]+ failed' "$OUT/console.log" | tail -n 1 || true)"
if [ -z "$line" ]; then
  echo "fw_core_avr: FAILED: no 'N passed, N failed' line from simavr (exit $sim_rc);" \
       "see $OUT/simavr.log" >&2
  exit 1
fi
passed="${line%% passed*}"
failed="${line#*, }"
failed="${failed%% failed*}"

echo "avr-size of the core ($MCU, -Os; berkeley text includes .rodata):"
avr-size -t "${core_objs[@]}" | sed "s#$OUT/##"
# Per section: flash holds text, rodata and data's initialisers; static RAM holds data and bss,
# and on the AVR (not on the dsPIC, whose XC16 reads constants through PSV) also .rodata.
avr-size -A "${core_objs[@]}" | awk '
  $1 ~ /^\.text/   { text += $2 }
  $1 ~ /^\.rodata/ { ro += $2 }
  $1 ~ /^\.data/   { data += $2 }
  $1 ~ /^\.bss/    { bss += $2 }
  END { printf "core: flash %d B (text %d + rodata %d + data %d), static RAM %d B (data+bss; " \
               "+%d B rodata copied to RAM on the AVR); a board_t instance is extra, see sizes above\n",
               text + ro + data, text, ro, data, data + bss, ro }'
echo "avr-size of the whole test image:"
avr-size "$OUT/fw_core_test.elf" | sed "s#$OUT/##"

echo "$line"
if [ "$failed" -ne 0 ] || [ "$passed" -le 0 ]; then
  exit 1
fi
exit 0
