#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, and runs the paper's scenario
# (Otter USV, gyro bias on 20-40 s, accelerometer bias on 60-80 s) through the DDS
# microservice on this host only (UDPv4 on 127.0.0.1): simulator publisher -> sidecar ->
# shore monitor. Shows the two faults raised, isolated with their C_i, and cleared; then a
# late-joining monitor, an acknowledgement and a clean shutdown. Takes ~30 s and stops every
# process it started.
#
#   scripts/demo.sh            the DDS demo (SPEED=10: data time per wall time)
#   scripts/demo.sh --offline  the same scenario through the offline replay (CSV -> JSON Lines)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
mode="${1:-dds}"
case "$mode" in
  dds | --dds) mode=dds ;;
  --offline) mode=offline ;;
  *) echo "usage: scripts/demo.sh [--offline]" >&2; exit 64 ;;
esac
build="${BUILD_DIR:-build}"
"$root/scripts/install-deps.sh"
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" >/dev/null
cmake --build "$build" -j "$(nproc)" --target usv-fdi
exe="$root/$build/usv-fdi"
out="${DEMO_OUT:-$root/$build/demo}"
mkdir -p "$out"

if [[ "$mode" == offline ]]; then
  echo "== simulating the paper's scenario on the Otter USV (50 Hz, noise-free as in the paper)"
  "$exe" sim --vessel otter --scenario paper --rate 50 --noise-scale 0 --output "$out/paper.csv"
  echo "== replaying it through the FDI engine"
  "$exe" replay --config config/scenarios/paper.yaml --input "$out/paper.csv" \
    --output "$out/paper.jsonl"
  echo "== fault events"
  grep '"type":"event"' "$out/paper.jsonl"
  echo "== summary"
  tail -n 1 "$out/paper.jsonl"
  exit 0
fi

# ----------------------------------------------------------------------------- DDS demo
speed="${SPEED:-10}"
mmsi=257000001
domain="${DEMO_DOMAIN:-$((100 + $$ % 100))}"
dds=(--domain "$domain" --partition "usv_fdi_demo_$$" --participant-profile usv_fdi_participant_loopback)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
}
trap cleanup EXIT
trap 'exit 130' INT TERM
wait_for() {  # file text seconds
  local end=$((SECONDS + $3))
  until grep -q -- "$2" "$1" 2>/dev/null; do
    if ((SECONDS >= end)); then
      echo "demo: '$2' did not appear in $1 within $3 s:" >&2
      cat "$1" >&2
      exit 1
    fi
    sleep 0.1
  done
}

echo "== DDS domain $domain on 127.0.0.1 only; logs in $out"
echo "== 1. the sidecar for MMSI $mmsi (usv-fdi run, the paper's engine settings)"
"$exe" run --config config/scenarios/paper.yaml --mmsi "$mmsi" --reliable-inputs "${dds[@]}" \
  2>"$out/sidecar.log" &
sidecar=$!
pids+=("$sidecar")
wait_for "$out/sidecar.log" "waiting for INS and rudder" 20

echo "== 2. the shore monitor (usv-fdi monitor): its table is printed on every change"
"$exe" monitor "${dds[@]}" 2>"$out/monitor.log" &
pids+=("$!")
wait_for "$out/sidecar.log" "1 fault-event reader(s)" 20

echo "== 3. the simulator publishes 100 s of the paper's scenario at ${speed}x real time"
echo "      (usv-fdi sim --publish: INS and rudder samples, noise-free as in the paper)"
timeout 300 "$exe" sim --publish --mmsi "$mmsi" --vessel otter --scenario paper --noise-scale 0 \
  --speed "$speed" --reliable --linger 0.5 "${dds[@]}" 2>"$out/sim.log"
sleep 1.5  # the sidecar notices the silence after 1 s: both channels stale
echo "   (the voyage is over: the INS falls silent, and after 1 s the sidecar raises both"
echo "    channels as stale, as it would for a dead INS at sea)"
echo
echo "== 4. what the sidecar logged"
grep -E "fault event|no INS sample" "$out/sidecar.log" | sed 's/^usv-fdi: [a-z]*: /   /'
echo
echo "== 5. a monitor that joins now still receives the latched state of every instance"
"$exe" monitor "${dds[@]}" --once --expect 2 --status --duration 10 2>>"$out/monitor.log"
echo
gyro_seq=$("$exe" monitor "${dds[@]}" --once --expect 2 --json --duration 10 2>>"$out/monitor.log" |
  sed -n 's/.*"sensor":"gyro".*"sequence":\([0-9]*\).*/\1/p')
echo "== 6. the operator acknowledges the gyro's latched event #$gyro_seq"
"$exe" monitor "${dds[@]}" --ack "$mmsi:gyro:$gyro_seq" --operator demo
echo "   ...and a stale acknowledgement (#1) is refused with its reason:"
"$exe" monitor "${dds[@]}" --ack "$mmsi:gyro:1" --operator demo --ack-timeout 1 || true
grep "refused" "$out/sidecar.log" | sed 's/^usv-fdi: [a-z]*: /   sidecar: /'
sleep 0.5
echo
echo "== 7. SIGINT: the sidecar stops its threads, deletes its DDS entities and exits 0"
kill -INT "$sidecar"
wait "$sidecar"
echo "   exit code $?; $(grep -o 'stopped in .*' "$out/sidecar.log")"
sleep 0.5
