#!/usr/bin/env bash
# Runs docker/setup-runtime.sh twice (idempotent) against a scratch root holding copies of this
# machine's account files, and checks the user and directories it promises. Needs root (useradd);
# exit 77 (skipped) otherwise.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
[ "$(id -u)" -eq 0 ] || { echo "SKIP: needs root (useradd --prefix)"; exit 77; }
root="$(mktemp -d)"
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/etc"
for f in passwd group shadow gshadow login.defs; do
  [ -e "/etc/$f" ] && cp "/etc/$f" "$root/etc/"
done
"$here/setup-runtime.sh" "$root" >/dev/null
"$here/setup-runtime.sh" "$root" >/dev/null
fail() { echo "FAIL: $*"; exit 1; }
[ "$(grep -c '^usv-fdi:' "$root/etc/passwd")" -eq 1 ] || fail "user usv-fdi not made exactly once"
grep -q '^usv-fdi:x:10001:10001::/var/lib/usv-fdi:/usr/sbin/nologin$' "$root/etc/passwd" ||
  fail "user entry: $(grep '^usv-fdi:' "$root/etc/passwd")"
[ "$(stat -c %u:%g:%a "$root/run/usv-fdi")" = 10001:10001:750 ] || fail "/run/usv-fdi"
[ "$(stat -c %u:%g:%a "$root/var/lib/usv-fdi")" = 10001:10001:750 ] || fail "/var/lib/usv-fdi"
[ -d "$root/etc/usv-fdi" ] || fail "/etc/usv-fdi"
! grep -q '^usv-fdi:' /etc/passwd || echo "note: this machine has a usv-fdi user of its own"
echo "ok: setup-runtime.sh makes user usv-fdi (10001) and its directories, idempotently"
