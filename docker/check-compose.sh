#!/usr/bin/env bash
# Checks docker/compose.yaml without a Docker engine:
#   1. it is exactly `docker/make-compose.sh 3` (no hand edits that the generator would lose);
#   2. `docker-compose config` (or `docker compose config`) accepts it and a 5-vessel fleet,
#      when a compose client is installed (scripts/packages.txt [test]: docker-compose); exit 77
#      (skipped) when none is;
#   3. the resolved file has what docker/README.md promises: two discovery servers, a shore monitor,
#      a sidecar and a simulator per vessel, the simulator in its sidecar's network AND IPC
#      namespaces, ROS_DISCOVERY_SERVER on every usv-fdi service;
#   4. the same for docker/compose.secure.yaml (make-compose.sh --secure 3), and the PKI command in
#      its header, run here, makes a participant profile for every --participant-profile it uses;
#   5. the commands: each vessel's sidecar and simulator in partition vessel-<MMSI>, the shore in
#      vessel-*, the sidecar on config/scenarios/paper.yaml with RELIABLE inputs, no
#      ROS_DISCOVERY_SERVER on the discovery servers;
#   6. the namespace fleet test (tests/fleet/service_fleet.*) runs the same topology: discovery
#      servers, addresses, participant profiles, partitions, engine config (a guard against drift).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$here/make-compose.sh" 3 >"$work/compose3.yaml"
if ! diff -u "$here/compose.yaml" "$work/compose3.yaml"; then
  echo "FAIL: docker/compose.yaml differs from docker/make-compose.sh 3 (regenerate it)"
  exit 1
fi
"$here/make-compose.sh" --secure 3 >"$work/secure3.yaml"
if ! diff -u "$here/compose.secure.yaml" "$work/secure3.yaml"; then
  echo "FAIL: docker/compose.secure.yaml differs from docker/make-compose.sh --secure 3 (regenerate it)"
  exit 1
fi
echo "ok: docker/compose.yaml and compose.secure.yaml are make-compose.sh's output for 3 vessels"

# The PKI command of the secure file's header, run into a scratch directory.
pki_cmd="$(sed -n '/^#   scripts\/make-security.sh/,/--initial-peers/p' "$here/compose.secure.yaml" |
  sed 's/^#[[:space:]]*//; s/\\$//' | tr '\n' ' ')"
pki_cmd="${pki_cmd/scripts\/make-security.sh docker\/pki/$here/../scripts/make-security.sh $work/pki}"
eval "$pki_cmd" >/dev/null || { echo "FAIL: the PKI command of compose.secure.yaml failed: $pki_cmd"; exit 1; }
for p in $(grep -o 'usv_fdi_secure_[A-Za-z0-9_.-]*_unicast' "$here/compose.secure.yaml" | sort -u); do
  grep -q "profile_name=\"$p\"" "$work/pki/security_profiles.xml" ||
    { echo "FAIL: compose.secure.yaml uses profile $p, which its PKI command does not make"; exit 1; }
done
grep -q 'file:///etc/usv-fdi/security/governance.p7s' "$work/pki/security_profiles.xml" ||
  { echo "FAIL: the PKI's profiles do not point into /etc/usv-fdi/security"; exit 1; }
echo "ok: compose.secure.yaml's PKI command makes every participant profile it uses"

# 6. The namespace fleet test runs what compose.yaml describes.
fleet_test="$here/../tests/fleet"
for want in "ROS_DISCOVERY_SERVER=10.77.0.2:11811;10.77.0.3:11811" "usv_fdi_discovery_server_udp@" \
  '"/docker/fleet_participants.xml"' '"usv_fdi_participant"' '"usv_fdi_fleet_udp"' '"vessel-*"' \
  '"vessel-" + std::to_string(mmsi(i))' "/config/scenarios/paper.yaml" '"--reliable-inputs"' \
  '"--reliable"' '257000000u + i' '"11811"'; do
  grep -qF -- "$want" "$fleet_test/service_fleet.hpp" "$fleet_test/service_fleet.cpp" ||
    { echo "FAIL: the fleet test (tests/fleet/service_fleet.*) no longer has $want"; exit 1; }
done
for want in 'd0) echo "$FLEET_SUBNET.2"' 'd1) echo "$FLEET_SUBNET.3"' '"$FLEET_SUBNET.5/24"' \
  'echo "$FLEET_SUBNET.$((10 + ${2#v}))"'; do
  grep -qF -- "$want" "$fleet_test/netns.sh" ||
    { echo "FAIL: tests/fleet/netns.sh no longer has $want (compose's addresses)"; exit 1; }
done
grep -qF 'ROS_DISCOVERY_SERVER: "$discovery"' "$here/make-compose.sh" &&
  grep -qF 'discovery="$subnet.2:11811;$subnet.3:11811"' "$here/make-compose.sh" ||
  { echo "FAIL: make-compose.sh's discovery servers differ from the fleet test's"; exit 1; }
echo "ok: the namespace fleet test runs compose.yaml's topology (servers, addresses, profiles, partitions, config)"

# block FILE SERVICE: the lines of SERVICE in a resolved compose file; command FILE SERVICE: its
# command as one line.
block() { awk -v s="  $2:" '$0 == s { on = 1; next } on && /^  [^ ]/ { exit } on' "$1"; }
command_of() { block "$1" "$2" | awk '/^    command:$/ { on = 1; next } on && /^    - / { sub(/^    - /, ""); gsub(/\x27/, ""); printf "%s ", $0; next } on { exit }'; }

compose=()
if command -v docker-compose >/dev/null 2>&1; then
  compose=(docker-compose)
elif docker compose version >/dev/null 2>&1; then
  compose=(docker compose)
else
  echo "SKIP: no compose client (docker-compose or the docker compose plugin) to validate with"
  exit 77
fi
"$here/make-compose.sh" 5 >"$work/compose5.yaml"
for f in "$here/compose.yaml" "$work/compose5.yaml" "$here/compose.secure.yaml"; do
  if ! "${compose[@]}" -f "$f" config >"$work/resolved.yaml"; then
    echo "FAIL: ${compose[*]} config refuses $(basename "$f")"
    exit 1
  fi
  n="$(grep -c '^  vessel[0-9]*-sim:$' "$work/resolved.yaml")"
  grep -q "^  shore:$" "$work/resolved.yaml" || { echo "FAIL: service shore missing"; exit 1; }
  for i in $(seq 1 "$n"); do
    grep -q "^  vessel$i:$" "$work/resolved.yaml" || { echo "FAIL: vessel$i missing"; exit 1; }
    grep -q "network_mode: service:vessel$i$" "$work/resolved.yaml" ||
      { echo "FAIL: vessel$i-sim not in vessel$i's network namespace"; exit 1; }
    grep -q "ipc: service:vessel$i$" "$work/resolved.yaml" ||
      { echo "FAIL: vessel$i-sim not in vessel$i's IPC namespace"; exit 1; }
  done
  for i in $(seq 1 "$n"); do
    mmsi=$((257000000 + i))
    c="$(command_of "$work/resolved.yaml" "vessel$i")"
    for w in "--partition vessel-$mmsi " "--config /usr/local/share/usv-fdi/config/scenarios/paper.yaml " \
      "--mmsi $mmsi " "--reliable-inputs "; do
      [[ "$c" == *"$w"* ]] || { echo "FAIL: vessel$i's sidecar lacks '$w': $c"; exit 1; }
    done
    c="$(command_of "$work/resolved.yaml" "vessel$i-sim")"
    for w in "--partition vessel-$mmsi " "--mmsi $mmsi " "--reliable "; do
      [[ "$c" == *"$w"* ]] || { echo "FAIL: vessel$i-sim lacks '$w': $c"; exit 1; }
    done
  done
  c="$(command_of "$work/resolved.yaml" shore)"
  [[ "$c" == *"--partition vessel-* "* ]] || { echo "FAIL: the shore is not in partition vessel-*: $c"; exit 1; }
  want=$((2 * n + 1))
  if [[ "$f" == *secure* ]]; then
    ! grep -q '^  discovery' "$work/resolved.yaml" || { echo "FAIL: discovery server in the secure fleet"; exit 1; }
    got="$(grep -c ':/etc/usv-fdi/security:ro$' "$work/resolved.yaml")"
    [ "$got" -eq "$want" ] || { echo "FAIL: PKI mounted in $got of $want usv-fdi services"; exit 1; }
    got="$(grep -c 'FASTRTPS_DEFAULT_PROFILES_FILE: /etc/usv-fdi/security/security_profiles.xml' "$work/resolved.yaml")"
    [ "$got" -eq "$want" ] || { echo "FAIL: security profiles on $got of $want usv-fdi services"; exit 1; }
  else
    for svc in discovery0 discovery1; do
      grep -q "^  $svc:$" "$work/resolved.yaml" || { echo "FAIL: service $svc missing"; exit 1; }
      ! block "$work/resolved.yaml" "$svc" | grep -q ROS_DISCOVERY_SERVER ||
        { echo "FAIL: $svc has ROS_DISCOVERY_SERVER (a 2.9 server aborts with it)"; exit 1; }
    done
    got="$(grep -c 'ROS_DISCOVERY_SERVER: 10.77.0.2:11811;10.77.0.3:11811' "$work/resolved.yaml")"
    [ "$got" -eq "$want" ] || { echo "FAIL: ROS_DISCOVERY_SERVER on $got of $want usv-fdi services"; exit 1; }
  fi
  echo "ok: ${compose[*]} config accepts $(basename "$f"): $n vessels, sidecar + simulator each"
done
