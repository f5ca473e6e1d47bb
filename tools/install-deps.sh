#!/usr/bin/env bash
# Installs CrunchBot's build and test dependencies from Debian 12 packages.
# Idempotent: packages already installed are left alone. Uses sudo when not root.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libode-dev libcairo2-dev libusb-1.0-0-dev
  catch2 libbenchmark-dev libcli11-dev nlohmann-json3-dev libyaml-cpp-dev help2man file
  libcpp-httplib-dev chromium
  gcc-avr avr-libc simavr
  umockdev libumockdev-dev
  python3-serial
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1
  fi
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
