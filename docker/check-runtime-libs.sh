#!/usr/bin/env bash
# Fails unless every shared library that the given executables load comes from a Debian package
# listed in the [runtime] section of scripts/packages.txt (or from the base image's libc6,
# libgcc-s1, libstdc++6), so the slim runtime image cannot miss one. Prints the packages used.
#   docker/check-runtime-libs.sh EXE...
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
[ $# -ge 1 ] || { echo "usage: check-runtime-libs.sh EXE..." >&2; exit 2; }
mapfile -t runtime < <("$here/../scripts/install-deps.sh" --list --only runtime)
base=(libc6 libgcc-s1 libstdc++6)
# Every package that a [runtime] package pulls in is present too: allow its dependencies.
mapfile -t allowed < <(
  printf '%s\n' "${base[@]}" "${runtime[@]}"
  apt-cache depends --recurse --no-recommends --no-suggests --no-conflicts --no-breaks \
    --no-replaces --no-enhances "${runtime[@]}" 2>/dev/null | grep -v '^ ' | grep -v '^<' || true
)
status=0
used=()
for exe in "$@"; do
  [ -x "$exe" ] || { echo "check-runtime-libs: not an executable: $exe" >&2; exit 2; }
  if ldd "$exe" | grep -q 'not found'; then
    echo "check-runtime-libs: $exe: unresolved libraries:" >&2
    ldd "$exe" | grep 'not found' >&2
    status=1
  fi
  while read -r lib; do
    real="$(readlink -f "$lib")"
    pkg="$(dpkg -S "$real" 2>/dev/null | head -n1 | cut -d: -f1 || true)"
    [ -n "$pkg" ] || pkg="$(dpkg -S "$lib" 2>/dev/null | head -n1 | cut -d: -f1 || true)"
    if [ -z "$pkg" ]; then
      echo "check-runtime-libs: $exe needs $lib, which no Debian package owns" >&2
      status=1
    elif ! printf '%s\n' "${allowed[@]}" | grep -qx "$pkg"; then
      echo "check-runtime-libs: $exe needs $lib from '$pkg': add it to [runtime] in scripts/packages.txt" >&2
      status=1
    else
      used+=("$pkg")
    fi
  done < <(ldd "$exe" | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }')
done
if [ "$status" -eq 0 ]; then
  echo "check-runtime-libs: ok, from: $(printf '%s\n' "${used[@]}" | sort -u | tr '\n' ' ')"
fi
exit "$status"
