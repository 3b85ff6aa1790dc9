#!/usr/bin/env bash
# The README's demo command: installs what is missing, builds, and runs the paper's
# scenario (gyro fault on 20-40 s, accelerometer fault on 60-80 s) through the simulator
# and the offline replay, printing the fault events with their isolation confidences.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
"$root/scripts/build.sh" -DUSV_FDI_BUILD_TESTS=OFF -DUSV_FDI_BUILD_BENCH=OFF
out="${DEMO_OUT:-$root/build/demo}"
mkdir -p "$out"
echo "== simulating the paper's scenario on the Otter USV (50 Hz, noise-free as in the paper)"
./build/usv-fdi sim --vessel otter --scenario paper --rate 50 --noise-scale 0 --output "$out/paper.csv"
echo "== replaying it through the FDI engine"
./build/usv-fdi replay --config config/scenarios/paper.yaml --input "$out/paper.csv" \
  --output "$out/paper.jsonl"
echo "== fault events"
grep '"type":"event"' "$out/paper.jsonl"
echo "== summary"
tail -n 1 "$out/paper.jsonl"
