#!/usr/bin/env bash
# The man page (host/app/CMakeLists.txt: help2man from --help): crunchhost.1 exists, is a man
# page of section 1, and holds every option `crunchhost --help` and each subcommand's --help
# print (so it cannot fall behind the program), without the build tree's path.
#   man_test.sh CRUNCHHOST MAN_PAGE
set -euo pipefail
host=$1
page=$2
[ -s "$page" ] || { echo "man_test: $page missing or empty" >&2; exit 1; }
grep -q '^\.TH CRUNCHHOST "1"' "$page" || { echo "man_test: no .TH CRUNCHHOST 1 header" >&2; exit 1; }
# roff writes --flag as \-\-flag; compare without the escapes.
text=$(sed 's/\\-/-/g; s/\\fB//g; s/\\fR//g; s/\\fI//g' "$page")
if grep -q "$(dirname "$host")" <<<"$text"; then
  echo "man_test: the page names the build tree" >&2
  exit 1
fi
checked=0
for sub in "" train sweep sweep-merge sweep-chart export; do
  # shellcheck disable=SC2086
  for opt in $("$host" $sub --help | grep -oE -- '--[a-z][a-z0-9-]*' | sort -u); do
    if ! grep -qF -- "$opt" <<<"$text"; then
      echo "man_test: ${sub:-crunchhost} option $opt is not in $page" >&2
      exit 1
    fi
    checked=$((checked + 1))
  done
done
[ "$checked" -gt 50 ] || { echo "man_test: only $checked options found in --help" >&2; exit 1; }
grep -q "SUBCOMMANDS" <<<"$text"
grep -q "ros-map" <<<"$text"
echo "man_test: $checked options of --help found in $page"
