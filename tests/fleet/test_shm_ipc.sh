#!/usr/bin/env bash
# Why docker/compose.yaml shares the IPC namespace wherever it shares a network namespace
# (docker/README.md, "Network, IPC and Fast DDS shared memory"). Two participants in ONE network
# namespace of our own (same hostname and addresses, so Fast DDS gives them the same host id and
# talks shared memory), discovering each other over UDP through a discovery server on 127.0.0.1,
# the reader with a private /dev/shm (a new mount namespace), as a container without
# `ipc: service:X` would have:
#   1. builtin transports (SHM + UDPv4): the reader receives NOTHING;
#   2. control, same but /dev/shm shared: the reader receives every latched instance;
#   3. the remedy without shared IPC, the UDP-only profile (usv_fdi_fleet_udp): the reader with the
#      private /dev/shm receives every instance.
#   test_shm_ipc.sh PROBE QOS_PROFILES
# Exit 77 (ctest SKIP_RETURN_CODE) without network namespaces or `unshare --mount`.
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
probe="$1"
qos="$2"
# shellcheck source=netns_preamble.sh
source "$here/netns_preamble.sh"
netns_test_begin sh 10
if ! unshare --mount sh -c 'mount -t tmpfs tmpfs /dev/shm' 2>/dev/null; then
  echo "SKIP: cannot make a private /dev/shm (unshare --mount; mount tmpfs)"
  exit 77
fi
fleet_netns_up "$name" 1 || fail "namespace not made"
export FASTRTPS_DEFAULT_PROFILES_FILE="$here/../../docker/fleet_participants.xml"
export ROS_DISCOVERY_SERVER="127.0.0.1:11811"
fleet_netns_exec "$name" v1 fastdds discovery -i 0 -l 127.0.0.1 -p 11811 \
  -x "usv_fdi_discovery_server_udp@$FASTRTPS_DEFAULT_PROFILES_FILE" >"$work/server.log" 2>&1 &

# start_publisher PROFILE DOMAIN: 2 latched instances, in the vessel namespace, shared /dev/shm.
start_publisher() {
  fleet_netns_exec "$name" v1 "$probe" publish-faults --profiles "$qos" --participant-profile "$1" \
    --domain "$2" --partition shm --vessels 1 --sensors 2 --timeout 60 >"$work/pub_$2.log" 2>&1 &
  for _ in $(seq 100); do
    grep -q '^published' "$work/pub_$2.log" 2>/dev/null && return 0
    sleep 0.1
  done
  fail "publisher on domain $2 did not start"
}
# read_instances PROFILE DOMAIN private|shared TIMEOUT -> number of instances received
read_instances() {
  local cmd=("$probe" read-faults --profiles "$qos" --participant-profile "$1" --domain "$2"
    --partition shm --expect 2 --timeout "$4" --settle-ms 200)
  if [ "$3" = private ]; then
    fleet_netns_exec "$name" v1 unshare --mount sh -c \
      'mount -t tmpfs tmpfs /dev/shm && exec "$@"' sh "${cmd[@]}" >"$work/read_$2_$3.log" 2>&1
  else
    fleet_netns_exec "$name" v1 "${cmd[@]}" >"$work/read_$2_$3.log" 2>&1
  fi
  grep -c '^instance ' "$work/read_$2_$3.log"
}

start_publisher usv_fdi_participant 21
got="$(read_instances usv_fdi_participant 21 private 4)"
[ "$got" -eq 0 ] || fail "SHM profile, private /dev/shm: expected nothing, got $got instances"
echo "ok: same host id, private /dev/shm, shared-memory transport: nothing arrives (4 s)"
got="$(read_instances usv_fdi_participant 21 shared 10)"
[ "$got" -eq 2 ] || fail "SHM profile, shared /dev/shm: expected 2 instances, got $got"
echo "ok: same host id, shared /dev/shm (ipc shared): both instances arrive"

start_publisher usv_fdi_fleet_udp 22
got="$(read_instances usv_fdi_fleet_udp 22 private 10)"
[ "$got" -eq 2 ] || fail "UDP-only profile, private /dev/shm: expected 2 instances, got $got"
echo "ok: same host id, private /dev/shm, UDP-only profile: both instances arrive"
