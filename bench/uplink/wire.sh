#!/usr/bin/env bash
# The status uplink on the wire (issue 13, section 5; docs/benchmark.md, "Status uplink"):
# ship-to-shore bytes counted on a real link. Two network namespaces joined by a veth pair: the
# ship (the real sidecar, `usv-fdi run`, with no INS: it publishes its status only) and the shore
# (a Fast DDS discovery server and the real `usv-fdi monitor --json --status`), in the documented
# fleet configuration (docker/fleet_participants.xml, profile usv_fdi_fleet_udp: UDPv4, clients of
# the discovery server through ROS_DISCOVERY_SERVER). For each uplink mode (periodic, then
# event) fresh processes run; after a warm-up the ship end's byte and packet counters (both
# directions) are read over a window, and the statuses the monitor printed in it counted. The
# difference between the modes, divided by the difference in statuses, is what one status costs
# on the link (RTPS DATA, heartbeats, ACKNACKs, UDP/IPv4); the rest is discovery and liveliness,
# the same for both.
#
#   bench/uplink/wire.sh [BUILD_DIR] [WINDOW_S]      (root: it makes network namespaces)
#
# Not a test: prints the figures.
set -euo pipefail

build=${1:-build}
window=${2:-60}
warmup=15
port=11811
here=$(cd "$(dirname "$0")/../.." && pwd)
bin=$(cd "$build" && pwd)/usv-fdi
server=/usr/bin/fast-discovery-server
fleet_xml=${FLEET_XML:-$here/docker/fleet_participants.xml}
[[ -x $bin ]] || { echo "wire.sh: no $bin (build first)" >&2; exit 1; }
[[ -x $server ]] || { echo "wire.sh: no $server (package fastdds-tools)" >&2; exit 1; }
[[ $(id -u) == 0 ]] || { echo "wire.sh: needs root (ip netns)" >&2; exit 1; }

ship=usvfdi-ship-$$
shore=usvfdi-shore-$$
ship_ip=10.203.91.1
shore_ip=10.203.91.2
work=$(mktemp -d)
stop_all() {
  for n in "$ship" "$shore"; do ip netns pids "$n" 2>/dev/null | xargs -r kill 2>/dev/null || true; done
  sleep 1
  for n in "$ship" "$shore"; do ip netns pids "$n" 2>/dev/null | xargs -r kill -9 2>/dev/null || true; done
}
cleanup() {
  stop_all
  ip netns del "$ship" 2>/dev/null || true
  ip netns del "$shore" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
ip netns add "$ship"
ip netns add "$shore"
ip link add "s$$" netns "$ship" type veth peer name "h$$" netns "$shore"
ip -n "$ship" addr add "$ship_ip/30" dev "s$$"
ip -n "$shore" addr add "$shore_ip/30" dev "h$$"
for n in "$ship" "$shore"; do ip -n "$n" link set lo up; done
ip -n "$ship" link set "s$$" up
ip -n "$shore" link set "h$$" up

counters() {  # the ship end, both directions: "bytes packets"
  ip netns exec "$ship" sh -c "d=/sys/class/net/s$$/statistics; \
    echo \$((\$(cat \$d/tx_bytes) + \$(cat \$d/rx_bytes))) \$((\$(cat \$d/tx_packets) + \$(cat \$d/rx_packets)))"
}

measure() {  # mode -> "bytes packets statuses"
  local mode=$1 cfg=$work/$1.yaml
  cat > "$cfg" <<EOF
model:
  B: [0.165394, -2.19400]
service:
  mmsi: 257000001
  qos_profiles: $here/config/qos/usv_fdi_profiles.xml
  participant_profile: usv_fdi_fleet_udp
  status_rate: 1
  status_uplink: {mode: $mode}
  input_timeout: 3600
  state_dir: ""
EOF
  ip netns exec "$shore" "$server" -i 0 -l "$shore_ip" -p "$port" \
    -x "usv_fdi_discovery_server_udp@$fleet_xml" > "$work/$mode.server" 2>&1 &
  sleep 1
  local env=(env "ROS_DISCOVERY_SERVER=$shore_ip:$port" "FASTRTPS_DEFAULT_PROFILES_FILE=$fleet_xml")
  ip netns exec "$shore" "${env[@]}" "$bin" monitor --json --status --domain 7 \
    --participant-profile usv_fdi_fleet_udp > "$work/$mode.mon" 2> /dev/null &
  ip netns exec "$ship" "${env[@]}" "$bin" run --config "$cfg" --domain 7 > "$work/$mode.log" 2>&1 &
  sleep "$warmup"
  local before after s0 s1
  before=$(counters)
  s0=$(grep -c '"type":"status"' "$work/$mode.mon" || true)
  sleep "$window"
  after=$(counters)
  s1=$(grep -c '"type":"status"' "$work/$mode.mon" || true)
  stop_all
  (( s1 > 0 )) || { echo "wire.sh: the monitor saw no status ($mode)" >&2; cat "$work/$mode.log" >&2; exit 1; }
  read -r b0 p0 <<< "$before"
  read -r b1 p1 <<< "$after"
  echo "$((b1 - b0)) $((p1 - p0)) $((s1 - s0))"
}

echo "status uplink on the wire: ship (sidecar, no INS) and shore (discovery server, monitor) in" \
  "two network namespaces joined by a veth pair, fleet profile (UDPv4, discovery server)," \
  "${warmup} s warm-up, ${window} s window, bytes and packets of both directions at the ship end"
read -r bp pp np <<< "$(measure periodic)"
read -r be pe ne <<< "$(measure event)"
echo "periodic: $bp bytes, $pp packets, $np statuses in ${window} s"
echo "event:    $be bytes, $pe packets, $ne statuses in ${window} s"
if (( np > ne )); then
  per=$(( (bp - be) / (np - ne) ))
  pkts=$(awk -v a="$pp" -v b="$pe" -v c="$np" -v d="$ne" 'BEGIN { printf "%.2f", (a - b) / (c - d) }')
  rest=$(( be - ne * per ))
  echo "one status on the link: $per bytes in $pkts packets (both directions)"
  echo "the rest (discovery, liveliness): $rest bytes per ${window} s," \
    "$(( rest * 3600 / window )) bytes per hour"
fi
