#!/usr/bin/env bash
# Self-test of tests/fleet/netns.sh: layout and addresses, no multicast, processes started in the
# namespaces are ended by `down`, and a setup that fails half-way leaves nothing behind.
# Exit 77 (ctest SKIP_RETURN_CODE) where namespaces cannot be made.
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck source=netns.sh
source "$here/netns.sh"
if ! reason="$(fleet_netns_check)"; then
  echo "SKIP: $reason"
  exit 77
fi
name="nh$(( $$ % 100000 ))"
trap 'fleet_netns_down "$name"' EXIT
trap 'exit 130' INT TERM
failures=0
check() { # check DESCRIPTION CMD...
  local what="$1"
  shift
  if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; failures=$((failures + 1)); fi
}

fleet_netns_up "$name" 3
check "up makes shore + 3 vessels" [ "$(fleet_netns_list "$name" | sort | tr '\n' ' ')" = "$name-shore $name-v1 $name-v2 $name-v3 " ]
check "shore bridge has 10.77.0.1/24" \
  bash -c "ip -n $name-shore -4 -o addr show dev br0 | grep -q ' 10.77.0.1/24 '"
for i in 1 2 3; do
  check "vessel $i eth0 has 10.77.0.$((10 + i))/24" \
    bash -c "ip -n $name-v$i -4 -o addr show dev eth0 | grep -q ' 10.77.0.$((10 + i))/24 '"
  check "vessel $i eth0 has no multicast" \
    bash -c "! ip -n $name-v$i link show dev eth0 | grep -q MULTICAST"
  check "vessel $i has no route but its own subnet" \
    bash -c "[ \"\$(ip -n $name-v$i -4 route show | awk '{print \$1}' | tr '\n' ' ')\" = '10.77.0.0/24 ' ]"
done
check "three bridge ports" bash -c "[ \$(ip -n $name-shore -o link show master br0 | wc -l) -eq 3 ]"
check "addr helper" [ "$(fleet_netns_addr "$name" v2)" = 10.77.0.12 ]
check "exec runs in the namespace" \
  bash -c "[ \"\$('$here/netns.sh' exec $name v3 ip -4 -o addr show dev eth0 | awk '{print \$4}')\" = 10.77.0.13/24 ]"
check "no veth left in the root namespace" bash -c "! ip -o link show | grep -q '${name}v'"

fleet_netns_exec "$name" v2 sleep 600 2>/dev/null &
sleeper=$!
sleep 0.3
fleet_netns_down "$name"
check "down removes every namespace" [ -z "$(fleet_netns_list "$name")" ]
sleep 0.2
check "down ends what ran inside" bash -c "! kill -0 $sleeper 2>/dev/null"
wait "$sleeper" 2>/dev/null || true

FLEET_SUBNET=10.77.300 fleet_netns_up "$name" 2 2>/dev/null
rc=$?
check "a failing setup reports failure" [ "$rc" -ne 0 ]
check "a failing setup leaves no namespace" [ -z "$(fleet_netns_list "$name")" ]
check "bad names are refused" bash -c "! '$here/netns.sh' up 'a-b' 1 2>/dev/null"
check "bad counts are refused" bash -c "! '$here/netns.sh' up $name 0 2>/dev/null"

[ "$failures" -eq 0 ] || { echo "$failures check(s) failed"; exit 1; }
