#!/usr/bin/env bash
# Installs every Debian package in scripts/packages.txt that is missing.
#   install-deps.sh                  all sections
#   install-deps.sh --only S [S...]  only the packages of sections S (build, test, runtime, ...)
#   install-deps.sh --list [--only S...]  print the selected package names and exit
#   install-deps.sh --clean ...      after installing, drop apt's caches and lists (images)
# Idempotent; needs root (or sudo) only when something is missing.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
list="$here/packages.txt"
only=()
print_only=0
clean=0
while [ $# -gt 0 ]; do
  case "$1" in
    --only)
      shift
      while [ $# -gt 0 ] && [ "${1#--}" = "$1" ]; do only+=("$1"); shift; done
      [ ${#only[@]} -gt 0 ] || { echo "install-deps: --only needs section names" >&2; exit 2; }
      ;;
    --list) print_only=1; shift ;;
    --clean) clean=1; shift ;;
    *) echo "install-deps: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
sections="$(sed -n 's/^\s*\[\([A-Za-z0-9_-]*\)\]\s*$/\1/p' "$list")"
for s in "${only[@]}"; do
  grep -qx "$s" <<<"$sections" || {
    echo "install-deps: no section [$s] in $list (have: $(echo $sections))" >&2
    exit 2
  }
done
# Package names of the selected sections, first occurrence only.
mapfile -t pkgs < <(awk -v want=" ${only[*]:-} " '
  /^[ \t]*(#|$)/ { next }
  /^[ \t]*\[[A-Za-z0-9_-]*\][ \t]*$/ { gsub(/[][ \t]/, ""); section = $0; next }
  { gsub(/[ \t]/, "") }
  (want == "  " || index(want, " " section " ")) && !seen[$0]++ { print }
' "$list")
if [ "$print_only" -eq 1 ]; then
  printf '%s\n' "${pkgs[@]%%|*}"
  exit 0
fi
# A line PACKAGE|COMMAND installs PACKAGE only when COMMAND is not on the PATH (Node.js and npm:
# a machine may have them from elsewhere, and Debian's npm would conflict with that nodejs).
missing=()
for entry in "${pkgs[@]}"; do
  p="${entry%%|*}"
  if [ "$p" != "$entry" ] && command -v "${entry#*|}" >/dev/null 2>&1; then continue; fi
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#pkgs[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends "${missing[@]}"
if [ "$clean" -eq 1 ]; then
  $SUDO apt-get clean
  $SUDO rm -rf /var/lib/apt/lists/*
fi
