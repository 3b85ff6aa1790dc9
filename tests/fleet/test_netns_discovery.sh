#!/usr/bin/env bash
# Two probe participants in two vessel namespaces find each other only through a Fast DDS
# discovery server (`fastdds discovery`) in the shore namespace: links without multicast, UDPv4
# only. First without the server (the reader must NOT find the publisher: no side channel), then
# with it (the reader receives every latched FaultEvent instance).
#
#   test_netns_discovery.sh PROBE QOS_PROFILES
# Exit 77 (ctest SKIP_RETURN_CODE) where namespaces cannot be made.
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
probe="$1"
qos="$2"
# shellcheck source=netns_preamble.sh
source "$here/netns_preamble.sh"
netns_test_begin ds 30
command -v fastdds >/dev/null || fail "fastdds not found (fastdds-tools)"

fleet_netns_up "$name" 2 || fail "namespaces not made"
server="$(fleet_netns_addr "$name" shore)"
port=11811
export FASTRTPS_DEFAULT_PROFILES_FILE="$here/../../docker/fleet_participants.xml"
export ROS_DISCOVERY_SERVER="$server:$port"
dds=(--profiles "$qos" --participant-profile usv_fdi_fleet_udp --domain 7 --partition fleet)

# The publisher on vessel 1 writes 2 latched instances and stays up.
fleet_netns_exec "$name" v1 "$probe" publish-faults "${dds[@]}" --vessels 1 --sensors 2 \
  --mmsi-base 257000001 --timeout 60 >"$work/publisher.log" 2>&1 &
for _ in $(seq 100); do
  grep -q '^published' "$work/publisher.log" 2>/dev/null && break
  sleep 0.1
done
grep -q '^published instances=2' "$work/publisher.log" || fail "publisher did not start"

# 1. No discovery server: nothing may be found (no multicast, no shared memory, no other path).
start=$(date +%s.%N)
fleet_netns_exec "$name" v2 "$probe" read-faults "${dds[@]}" --expect 1 --timeout 4 \
  >"$work/reader_without_server.log" 2>&1
rc=$?
[ "$rc" -eq 1 ] || fail "without a discovery server the reader exited $rc (expected 1: timeout)"
grep -q '^instance' "$work/reader_without_server.log" && fail "reader found the publisher without a server"
echo "ok: without a discovery server vessel 2 does not discover vessel 1 (4 s)"

# 2. The discovery server in the shore namespace, on the bridge address.
fleet_netns_exec "$name" shore fastdds discovery -i 0 -l "$server" -p "$port" \
  -x "usv_fdi_discovery_server_udp@$FASTRTPS_DEFAULT_PROFILES_FILE" >"$work/server.log" 2>&1 &
for _ in $(seq 50); do
  fleet_netns_exec "$name" shore ss -lun 2>/dev/null | grep -q ":$port " && break
  sleep 0.1
done
fleet_netns_exec "$name" shore ss -lun | grep -q ":$port " || fail "discovery server not listening"

start=$(date +%s%N)
fleet_netns_exec "$name" v2 "$probe" read-faults "${dds[@]}" --expect 2 --timeout 20 \
  --settle-ms 300 >"$work/reader.log" 2>&1
rc=$?
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
[ "$rc" -eq 0 ] || fail "with the discovery server the reader exited $rc"
for s in 0 1; do
  grep -q "^instance mmsi=257000001 sensor=$s state=1 " "$work/reader.log" ||
    fail "instance 257000001/$s missing"
done
echo "ok: through the discovery server at $server:$port vessel 2 received both instances of vessel 1 (${elapsed_ms} ms)"
