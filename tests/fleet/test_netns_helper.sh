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
check "up makes shore, 2 discovery hosts, 3 vessels" \
  [ "$(fleet_netns_list "$name" | sort | tr '\n' ' ')" = "$name-d0 $name-d1 $name-shore $name-v1 $name-v2 $name-v3 " ]
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
check "shore bridge also has 10.77.0.5/24 (compose's shore monitor)" \
  bash -c "ip -n $name-shore -4 -o addr show dev br0 | grep -q ' 10.77.0.5/24 '"
for d in 0 1; do
  check "discovery host d$d eth0 has 10.77.0.$((2 + d))/24" \
    bash -c "ip -n $name-d$d -4 -o addr show dev eth0 | grep -q ' 10.77.0.$((2 + d))/24 '"
done
check "five bridge ports" bash -c "[ \$(ip -n $name-shore -o link show master br0 | wc -l) -eq 5 ]"
check "addr helper" [ "$(fleet_netns_addr "$name" v2)" = 10.77.0.12 ]
check "exec runs in the namespace" \
  bash -c "[ \"\$('$here/netns.sh' exec $name v3 ip -4 -o addr show dev eth0 | awk '{print \$4}')\" = 10.77.0.13/24 ]"
# Each node has its own /dev/shm, shared by the processes on that node only.
fleet_netns_exec "$name" v1 sh -c 'echo v1 >/dev/shm/usv-fdi-netns-probe'
check "/dev/shm is shared on a node" \
  bash -c "[ \"\$('$here/netns.sh' exec $name v1 cat /dev/shm/usv-fdi-netns-probe)\" = v1 ]"
check "/dev/shm is private to a node" \
  bash -c "! '$here/netns.sh' exec $name v2 test -e /dev/shm/usv-fdi-netns-probe"
check "/dev/shm of the root namespace is untouched" [ ! -e /dev/shm/usv-fdi-netns-probe ]
# link: a partition between vessel 2 and the shore, and its end. Reachability: a TCP connection to
# a closed port of the shore is refused at once when the shore is reachable (no ping installed).
reaches_shore() {
  local out
  out="$(fleet_netns_exec "$name" "$1" timeout 3 bash -c \
    "exec 3<>/dev/tcp/$(fleet_netns_addr "$name" shore)/9" 2>&1)"
  [[ "$out" == *"Connection refused"* ]]
}
not() { ! "$@"; }
eventually_reaches_shore() { # the neighbour entry that failed while the link was down: ~0.3 s
  for _ in $(seq 20); do reaches_shore "$1" && return 0; sleep 0.25; done
  return 1
}
check "vessel 2 reaches the shore" reaches_shore v2
fleet_netns_link "$name" v2 down
check "link down: vessel 2 does not reach the shore" not reaches_shore v2
check "link down: vessel 3 still does" reaches_shore v3
fleet_netns_link "$name" v2 up
check "link up: vessel 2 reaches the shore again (within 5 s)" eventually_reaches_shore v2
check "vessel 3 reaches discovery host d1" bash -c "[[ \"\$('$here/netns.sh' exec $name v3 timeout 3 bash -c 'exec 3<>/dev/tcp/10.77.0.3/9' 2>&1)\" == *refused* ]]"
check "link refuses the shore" bash -c "! '$here/netns.sh' link $name shore down 2>/dev/null"
check "no veth left in the root namespace" bash -c "! ip -o link show | grep -q '${name}v'"

fleet_netns_exec "$name" v2 sleep 600 2>/dev/null &
sleeper=$!
sleep 0.3
fleet_netns_down "$name"
check "down removes every namespace" [ -z "$(fleet_netns_list "$name")" ]
check "down removes the nodes' /dev/shm" bash -c "! ls -d '$FLEET_SHM_ROOT/$name-'* 2>/dev/null"
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
