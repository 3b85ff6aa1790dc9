# The shell preamble of the network-namespace test scripts (sourced, not run): loads netns.sh
# next to it, and netns_test_begin PREFIX [LOG_TAIL] checks that namespaces can be made (else
# "SKIP: <reason>", exit 77), sets $name (PREFIX + pid) and $work (a scratch directory), removes
# both at exit, and defines fail MESSAGE (prints it and the tail of every $work/*.log, exit 1).
# shellcheck shell=bash
source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/netns.sh"

netns_test_begin() {
  local reason
  if ! reason="$(fleet_netns_check)"; then
    echo "SKIP: $reason"
    exit 77
  fi
  name="$1$(($$ % 100000))"
  log_tail="${2:-20}"
  work="$(mktemp -d)"
  trap 'fleet_netns_down "$name"; rm -rf "$work"' EXIT
  trap 'exit 130' INT TERM
}

fail() {
  echo "FAIL: $*"
  local f
  for f in "$work"/*.log; do
    [ -f "$f" ] && { echo "--- $(basename "$f")"; tail -n "$log_tail" "$f"; }
  done
  exit 1
}
