#!/usr/bin/env bash
# DDS Security across network namespaces, as a secure fleet without multicast runs it (Fast DDS 2.9
# has no secure discovery server): SIMPLE discovery by unicast to the fleet's addresses
# (make-security.sh --initial-peers), UDPv4 only. Vessel 1 runs a stand-in sidecar (vessel
# identity), the shore namespace an authorised shore monitor, vessel 2 an intruder holding a
# foreign CA's certificate with the shore's subject name. The shore must receive the latched
# events and its acks must reach the sidecar; the intruder must get nothing and inject nothing.
#
#   test_netns_security.sh SECURE_PROBE QOS_PROFILES MAKE_SECURITY
# Exit 77 (ctest SKIP_RETURN_CODE) where namespaces cannot be made.
set -uo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
probe="$1"
qos="$2"
make_security="$3"
# shellcheck source=netns_preamble.sh
source "$here/netns_preamble.sh"
netns_test_begin sc 20

fleet_netns_up "$name" 2 || fail "namespaces not made"
peers="$(fleet_netns_addr "$name" shore),$(fleet_netns_addr "$name" v1),$(fleet_netns_addr "$name" v2)"
"$make_security" "$work/fleet" --identity vessel:vessel:257000001 --identity shore:shore:257000001 \
  --initial-peers "$peers" >"$work/pki.log" 2>&1 || fail "make-security.sh (fleet)"
"$make_security" "$work/foreign" --ca-name "foreign CA" --identity 'shore:shore:*' \
  --initial-peers "$peers" >>"$work/pki.log" 2>&1 || fail "make-security.sh (foreign)"
# The vessel's partition: its identity may publish nowhere else.
dds=(--qos "$qos" --domain 7 --partition vessel-257000001)

fleet_netns_exec "$name" v1 "$probe" sidecar "${dds[@]}" --security "$work/fleet/security_profiles.xml" \
  --participant-profile usv_fdi_secure_vessel_unicast --mmsi 257000001 --sensors 2 --timeout 60 \
  >"$work/sidecar.log" 2>"$work/sidecar.err" &
for _ in $(seq 150); do
  grep -q '^ready' "$work/sidecar.log" 2>/dev/null && break
  sleep 0.1
done
grep -q '^ready' "$work/sidecar.log" || fail "sidecar did not start"

# The shore (control) stops 2 s after it has both events; the intruder runs from before the
# shore starts until after it has finished, then gets SIGTERM (and prints its summary).
peer=(peer "${dds[@]}" --read-faults 1 --write-acks 1 --duration 40 --mmsi 257000001)
# `ip netns exec` directly (not the shell function) so that $! is the probe itself.
ip netns exec "$name-v2" "$probe" "${peer[@]}" --write-ins 1 \
  --security "$work/foreign/security_profiles.xml" \
  --participant-profile usv_fdi_secure_shore_unicast --operator intruder \
  >"$work/intruder.log" 2>"$work/intruder.err" &
intruder_pid=$!
fleet_netns_exec "$name" shore "$probe" "${peer[@]}" --until-faults 2 \
  --security "$work/fleet/security_profiles.xml" \
  --participant-profile usv_fdi_secure_shore_unicast --operator shore-op \
  >"$work/shore.log" 2>"$work/shore.err"
shore_rc=$?
kill -TERM "$intruder_pid" 2>/dev/null
wait "$intruder_pid"
intruder_rc=$?
sleep 0.5

[ "$shore_rc" -eq 0 ] || fail "shore peer exited $shore_rc"
[ "$intruder_rc" -eq 0 ] || fail "intruder peer exited $intruder_rc"
grep -q '^summary faults=2 ' "$work/shore.log" || fail "the shore did not receive both latched events"
grep -q '^fault instance mmsi=257000001 sensor=1 sequence=1 message=secret fault of 257000001/1$' \
  "$work/shore.log" || fail "event content"
grep -q '^ack mmsi=257000001 sensor=0 sequence=1 operator=shore-op$' "$work/sidecar.log" ||
  fail "the shore's acks did not reach the sidecar"
echo "ok: authorised shore (shore namespace) <-> sidecar (vessel 1): events and acks, by unicast discovery"
grep -q '^summary faults=0 ' "$work/intruder.log" || fail "the intruder received events"
grep -q 'operator=intruder' "$work/sidecar.log" && fail "an intruder's ack reached the sidecar"
grep -q '^ins ' "$work/sidecar.log" && fail "an intruder's INS sample reached the sidecar"
grep -q '^ack_writer created$' "$work/intruder.log" || fail "intruder log incomplete"
echo "ok: foreign-CA intruder (vessel 2) read nothing and injected nothing"
