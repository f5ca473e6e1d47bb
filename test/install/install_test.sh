#!/usr/bin/env bash
# The installed package (issue 17; docs/INSTALL.md): `cmake --install` of the existing build
# directory into a temporary prefix (nothing is rebuilt), then a tiny consumer project
# (test/install/consumer) configured with find_package(Crunch) and built against it, run from the
# prefix's bin directory so that it must find the installed models. Also checks the installed
# crunchhost runs.
#   install_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix

cmake --install "$build" --prefix "$prefix" >"$work/install.log"
for f in bin/crunchhost bin/flash-whisker-board lib/udev/rules.d/99-crunchbot.rules \
         share/crunchbot/models/sim_models.json include/crunch/render/ros_map.h \
         include/whisker/bridge_frame.h lib/cmake/Crunch/CrunchConfig.cmake \
         lib/cmake/Crunch/CrunchTargets.cmake; do
  if [ ! -e "$prefix/$f" ]; then
    echo "install_test: $f not installed" >&2
    exit 1
  fi
done
"$prefix/bin/crunchhost" --version

cmake -S "$src/test/install/consumer" -B "$work/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >"$work/configure.log" || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/consumer" >"$work/build.log" || { cat "$work/build.log"; exit 1; }
# Beside an installed crunchhost, it must find the installed models.
cp "$work/consumer/crunch_consumer" "$prefix/bin/"
"$prefix/bin/crunch_consumer" "$prefix/share/crunchbot/models/sim_models.json"
echo "install_test: installed, consumer built and ran"
