#!/usr/bin/env bash
# Network-namespace test hosts for the fleet tests (issue 4): one shore namespace holding a bridge,
# two discovery-server hosts and N vessel namespaces, each joined to the bridge by a veth pair.
# Addresses are our own, those of docker/compose.yaml:
#   shore      NAME-shore  br0   10.77.0.1/24   (FLEET_SUBNET, default 10.77.0)
#                                and 10.77.0.5/24 (compose's shore monitor)
#   discovery  NAME-d0     eth0  10.77.0.2/24   (compose's discovery0)
#              NAME-d1     eth0  10.77.0.3/24   (compose's discovery1)
#   vessel i   NAME-v<i>   eth0  10.77.0.<10+i>/24            (i = 1..N, N <= 200)
# The links carry no multicast (multicast off, no route for it), so DDS discovery between
# namespaces works only through a unicast discovery server. There is no route out of the
# namespaces: every packet stays on links this script made.
#
# Each node is a host of its own, as a container is: its network namespace AND its own /dev/shm
# (a directory FLEET_SHM_ROOT/NAME-<node>, default root /dev/shm/usv-fdi-netns, bind-mounted on
# /dev/shm for every process `exec` starts on that node). Processes on one node share /dev/shm, so
# Fast DDS's shared-memory transport works between them (a vessel's simulator and sidecar, like
# two containers sharing an IPC namespace); processes on different nodes never see each other's
# segments, and what a killed participant leaves behind goes away with `down`.
#
#   netns.sh check                 exit 0 if namespaces can be made here, else print why; exit 77
#   netns.sh up NAME N             make NAME-shore, NAME-d0, NAME-d1 and NAME-v1..NAME-vN (removes
#                                  leftovers first; on any failure removes what it made and exits
#                                  non-zero)
#   netns.sh addr NAME NODE        print NODE's address (NODE: shore, d0, d1 or v<i>)
#   netns.sh exec NAME NODE CMD..  run CMD on NODE: its network namespace, its /dev/shm
#   netns.sh link NAME NODE up|down  take NODE's (v<i>, d0, d1) link to the shore bridge down (a
#                                  network partition: the shore-side end of its veth) or back up
#   netns.sh down NAME             kill what still runs in NAME-*, delete the namespaces and their
#                                  /dev/shm directories (idempotent)
#   netns.sh list NAME             print the namespaces of NAME
#
# Sourcing it instead defines fleet_netns_check/up/addr/exec/link/down/list. A caller sets a trap:
#   trap 'tests/fleet/netns.sh down NAME' EXIT
# NAME: letters and digits, at most 8 (interface names are limited to 15 bytes).
set -uo pipefail

FLEET_SUBNET="${FLEET_SUBNET:-10.77.0}"
FLEET_SHM_ROOT="${FLEET_SHM_ROOT:-/dev/shm/usv-fdi-netns}"

fleet_netns_check() {
  if ! command -v ip >/dev/null 2>&1; then
    echo "network namespaces unavailable: 'ip' not found (iproute2, scripts/packages.txt)"
    return 77
  fi
  if [ "$(id -u)" -ne 0 ]; then
    echo "network namespaces unavailable: needs root (CAP_SYS_ADMIN, CAP_NET_ADMIN); running as uid $(id -u)"
    return 77
  fi
  local probe="usvfdichk$$"
  local err
  if ! err="$(ip netns add "$probe" 2>&1)"; then
    echo "network namespaces unavailable: 'ip netns add' failed: $err"
    return 77
  fi
  if ! err="$(ip netns exec "$probe" ip link add chk0 type bridge 2>&1)"; then
    ip netns del "$probe" 2>/dev/null
    echo "network namespaces unavailable: cannot create links inside a namespace: $err"
    return 77
  fi
  ip netns del "$probe" 2>/dev/null
  return 0
}

_fleet_valid_name() {
  case "$1" in
    '' | *[!A-Za-z0-9]*) echo "netns.sh: NAME must be letters and digits: '$1'" >&2; return 2 ;;
  esac
  if [ "${#1}" -gt 8 ]; then echo "netns.sh: NAME longer than 8: '$1'" >&2; return 2; fi
}

fleet_netns_list() {
  _fleet_valid_name "$1" || return 2
  ip netns list 2>/dev/null | awk '{print $1}' | grep -E "^$1-(shore|d[01]|v[0-9]+)\$" || true
}

fleet_netns_addr() {
  case "$2" in
    shore) echo "$FLEET_SUBNET.1" ;;
    d0) echo "$FLEET_SUBNET.2" ;;
    d1) echo "$FLEET_SUBNET.3" ;;
    v[0-9]*) echo "$FLEET_SUBNET.$((10 + ${2#v}))" ;;
    *) echo "netns.sh: unknown node '$2' (shore, d0, d1 or v<i>)" >&2; return 2 ;;
  esac
}

# The directory mounted on NODE's /dev/shm.
fleet_netns_shm() { echo "$FLEET_SHM_ROOT/$1-$2"; }

# `ip netns exec` runs CMD in a new mount namespace already; `unshare --mount` makes that explicit
# before the bind mount, which therefore stays private to CMD (and its children). Every step
# execs the next, so CMD keeps the pid of the `ip` process (for `$!`, signals, PDEATHSIG).
fleet_netns_exec() {
  local name="$1" node="$2"
  shift 2
  ip netns exec "$name-$node" unshare --mount sh -c 'mount --bind "$0" /dev/shm && exec "$@"' \
    "$(fleet_netns_shm "$name" "$node")" "$@"
}

fleet_netns_link() {
  local name="$1" node="$2" state="$3"
  _fleet_valid_name "$name" || return 2
  case "$node" in v[0-9]* | d0 | d1) ;; *) echo "netns.sh: link: NODE must be v<i>, d0 or d1, not '$node'" >&2; return 2 ;; esac
  case "$state" in up | down) ;; *) echo "netns.sh: link: up or down, not '$state'" >&2; return 2 ;; esac
  _fleet_step ip -n "$name-shore" link set "${name}${node}s" "$state"
}

fleet_netns_down() {
  _fleet_valid_name "$1" || return 2
  local ns pid
  for ns in $(fleet_netns_list "$1"); do
    # Processes a test started in our namespace: TERM, then KILL what is left after 2 s.
    for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -TERM "$pid" 2>/dev/null; done
    for _ in $(seq 20); do
      [ -z "$(ip netns pids "$ns" 2>/dev/null)" ] && break
      sleep 0.1
    done
    for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -KILL "$pid" 2>/dev/null; done
    ip netns del "$ns" 2>/dev/null || true  # deleting a namespace deletes its veth ends
    rm -rf "$FLEET_SHM_ROOT/$ns"
  done
  rm -rf "$FLEET_SHM_ROOT/$1-"*  # also after a setup that failed half-way
  return 0
}

fleet_netns_up() {
  local name="$1" n="$2"
  _fleet_valid_name "$name" || return 2
  case "$n" in '' | *[!0-9]* | 0) echo "netns.sh: N must be 1..200: '$n'" >&2; return 2 ;; esac
  [ "$n" -le 200 ] || { echo "netns.sh: N must be 1..200: '$n'" >&2; return 2; }
  fleet_netns_down "$name"
  if ! _fleet_netns_make "$name" "$n"; then
    echo "netns.sh: setting up $name failed; removing what was made" >&2
    fleet_netns_down "$name"
    return 1
  fi
}

_fleet_step() { # runs one setup step; a failure is reported with the command that failed
  local err
  if ! err="$("$@" 2>&1)"; then
    echo "netns.sh: '$*' failed: $err" >&2
    return 1
  fi
}

# Every step is checked explicitly: `set -e` does not apply inside a function called from `if`.
_fleet_netns_make() {
  local name="$1" n="$2" shore="$1-shore" i
  _fleet_step ip netns add "$shore" || return 1
  _fleet_step mkdir -p "$(fleet_netns_shm "$name" shore)" || return 1
  _fleet_step ip -n "$shore" link set lo up || return 1
  _fleet_step ip -n "$shore" link add br0 type bridge || return 1
  _fleet_step ip -n "$shore" addr add "$FLEET_SUBNET.1/24" dev br0 || return 1
  _fleet_step ip -n "$shore" addr add "$FLEET_SUBNET.5/24" dev br0 || return 1
  _fleet_step ip -n "$shore" link set br0 multicast off || return 1
  _fleet_step ip -n "$shore" link set br0 up || return 1
  _fleet_add_host "$name" d0 || return 1
  _fleet_add_host "$name" d1 || return 1
  for i in $(seq 1 "$n"); do
    _fleet_add_host "$name" "v$i" || return 1
  done
}

# _fleet_add_host NAME NODE: namespace NAME-NODE with eth0 at NODE's address, on the shore bridge.
_fleet_add_host() {
  local name="$1" node="$2" shore="$1-shore" ns="$1-$2"
  local host="${name}${node}h" peer="${name}${node}s"  # <= 15 bytes
  _fleet_step ip netns add "$ns" || return 1
  _fleet_step mkdir -p "$(fleet_netns_shm "$name" "$node")" || return 1
  _fleet_step ip -n "$ns" link set lo up || return 1
  # Both ends leave the root namespace at once.
  _fleet_step ip link add "$host" netns "$ns" type veth peer name "$peer" netns "$shore" || return 1
  _fleet_step ip -n "$ns" link set "$host" name eth0 || return 1
  _fleet_step ip -n "$ns" addr add "$(fleet_netns_addr "$name" "$node")/24" dev eth0 || return 1
  _fleet_step ip -n "$ns" link set eth0 multicast off || return 1
  _fleet_step ip -n "$ns" link set eth0 up || return 1
  _fleet_step ip -n "$shore" link set "$peer" master br0 || return 1
  _fleet_step ip -n "$shore" link set "$peer" multicast off || return 1
  _fleet_step ip -n "$shore" link set "$peer" up || return 1
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  cmd="${1:-}"
  shift || true
  case "$cmd" in
    check) reason="$(fleet_netns_check)"; rc=$?; [ -z "$reason" ] || echo "$reason"; exit "$rc" ;;
    up) [ $# -eq 2 ] || { echo "usage: netns.sh up NAME N" >&2; exit 2; }; fleet_netns_up "$@" ;;
    down) [ $# -eq 1 ] || { echo "usage: netns.sh down NAME" >&2; exit 2; }; fleet_netns_down "$@" ;;
    list) [ $# -eq 1 ] || { echo "usage: netns.sh list NAME" >&2; exit 2; }; fleet_netns_list "$@" ;;
    addr) [ $# -eq 2 ] || { echo "usage: netns.sh addr NAME NODE" >&2; exit 2; }; fleet_netns_addr "$@" ;;
    exec) [ $# -ge 3 ] || { echo "usage: netns.sh exec NAME NODE CMD..." >&2; exit 2; }; fleet_netns_exec "$@" ;;
    link) [ $# -eq 3 ] || { echo "usage: netns.sh link NAME NODE up|down" >&2; exit 2; }; fleet_netns_link "$@" ;;
    *) echo "usage: netns.sh check | up NAME N | addr NAME NODE | exec NAME NODE CMD... | link NAME NODE up|down | down NAME | list NAME" >&2; exit 2 ;;
  esac
fi
