#!/usr/bin/env bash
# The .deb (issue 17; docs/INSTALL.md): `cpack -G DEB` from the existing build directory into a
# temporary directory (nothing is rebuilt), then the package's name, control fields and contents
# are checked, apt resolves it (simulated install), and its crunchhost, unpacked, runs.
#   deb_test.sh BUILD_DIR
set -euo pipefail
build=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work" >"$work/cpack.log" ||
  { cat "$work/cpack.log"; exit 1; }
shopt -s nullglob
debs=("$work"/crunchbot_*.deb)
if [ ${#debs[@]} -ne 1 ]; then
  echo "deb_test: expected one crunchbot_*.deb, got: ${debs[*]:-none}" >&2
  cat "$work/cpack.log"
  exit 1
fi
deb=${debs[0]}
echo "deb_test: $(basename "$deb"), $(stat -c %s "$deb") bytes"
[ "$(dpkg-deb -f "$deb" Package)" = crunchbot ]
depends=$(dpkg-deb -f "$deb" Depends)
echo "deb_test: Depends: $depends"
for lib in libcairo2 libusb-1.0-0 libode libyaml-cpp; do
  case "$depends" in
    *"$lib"*) ;;
    *) echo "deb_test: Depends lacks $lib" >&2; exit 1 ;;
  esac
done
contents=$(dpkg-deb -c "$deb")
for f in ./usr/bin/crunchhost ./usr/bin/flash-whisker-board ./usr/lib/udev/rules.d/99-crunchbot.rules \
         ./usr/share/crunchbot/models/sim_models.json ./usr/share/man/man1/crunchhost.1 ./usr/include/crunch/core/result.h \
         ./usr/lib/cmake/Crunch/CrunchConfig.cmake; do
  if ! grep -q " $f\$" <<<"$contents"; then
    echo "deb_test: $f not in the package" >&2
    exit 1
  fi
done
# What `apt install ./crunchbot_*.deb` would do, simulated (-s: nothing is installed): apt takes
# the file as a package and resolves its Depends.
apt_out=$(apt-get install -s "$deb" 2>&1) || { echo "$apt_out" >&2; exit 1; }
grep -q "^Inst crunchbot " <<<"$apt_out" || { echo "$apt_out" >&2; exit 1; }
dpkg-deb -x "$deb" "$work/root"
"$work/root/usr/bin/crunchhost" --version
echo "deb_test: package checked"
