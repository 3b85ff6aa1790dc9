#!/usr/bin/env bash
# What lost NMEA datagrams do to the faults raised, for both ways of holding a value on the
# sample grid (usv-fdi replay --nmea-hold due | max-age; docs/integration.md, "Lost datagrams").
#
#   scripts/bench-nmea-loss.sh [--every N] [--jitter MS] [--rsa-phase MS] [--seeds "1 2 3 4"]
#                              [--noise "0 0.2 1"] [--build DIR]
#
# For each vessel (otter, mariner), scenario (faults, healthy), seed and noise scale, the
# simulator writes the voyage as an NMEA log (ROT, RSA, VBW per 10 Hz sample, TAG times); a copy
# loses every N-th sample's datagram (its three lines). With --jitter, every line's TAG time
# c: of both logs moves by a uniform random -MS..+MS ms (seeded), as a sender's clock and
# scheduler would put it: the times then straddle the sample grid. With --rsa-phase, the RSA
# lines (the rudder: another sender, the steering gear) are sent MS ms later than the INS's
# ROT and VBW (and given that TAG time: the rudder angle then belongs to that later instant,
# a lag of MS ms the engine sees as such). Both logs are replayed with each hold.
# A raised event of the lossy replay with no raised event of the same sensor within 5 s in the
# lossless replay (same hold) is "invented"; one of the lossless replay with none in the lossy
# replay is "lost". Prints one table row per noise scale and hold (sums over the runs).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
every=37
jitter=0
rsa_phase=0
seeds="1 2 3 4"
noise="0 0.2 1"
build="$here/build"
while [ $# -gt 0 ]; do
  case "$1" in
    --every) every="$2"; shift 2 ;;
    --jitter) jitter="$2"; shift 2 ;;
    --rsa-phase) rsa_phase="$2"; shift 2 ;;
    --seeds) seeds="$2"; shift 2 ;;
    --noise) noise="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    *) echo "bench-nmea-loss: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[[ "$every" =~ ^[0-9]+$ ]] && [ "$every" -ge 2 ] || {
  echo "bench-nmea-loss: --every must be an integer >= 2, not '$every'" >&2
  exit 2
}
if [ ! -x "$build/usv-fdi" ]; then
  "$here/scripts/install-deps.sh" --only build >&2
  cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >&2
  cmake --build "$build" --target usv-fdi -j "$(nproc)" >&2
fi
exe="$build/usv-fdi"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

for ns in $noise; do
  for v in otter mariner; do
    for sc in faults healthy; do
      for seed in $seeds; do
        f="$work/ns$ns-$v-$sc-$seed"
        "$exe" sim --vessel "$v" --scenario "$sc" --rate 10 --seed "$seed" --noise-scale "$ns" \
          --nmea --output "$f.nmea" 2>/dev/null
        python3 - "$f.nmea" "$every" "$jitter" "$seed" "$rsa_phase" <<'EOF'
import random, re, sys
path, every, jitter_ms, seed = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
rsa_phase = int(sys.argv[5])
rng = random.Random(seed)

def in_ms(c):
    # the simulator writes whole seconds in seconds, the rest in milliseconds
    return c * 1000 if c < 10**11 else c

def jittered(line):
    # \s:..,c:MS*hh\$... : move c: and recompute the TAG block's checksum
    m = re.match(r"\\([^*]*)\*[0-9A-Fa-f]{2}\\(.*)", line)
    if not m or (jitter_ms == 0 and rsa_phase == 0):
        return line
    shift = rsa_phase if "RSA," in m.group(2) else 0
    body = re.sub(r"c:(\d+)", lambda c: "c:%d" % (in_ms(int(c.group(1))) + shift + round(rng.uniform(-jitter_ms, jitter_ms))), m.group(1))
    x = 0
    for ch in body:
        x ^= ord(ch)
    return "\\%s*%02X\\%s" % (body, x, m.group(2))

def tag_time(line):
    m = re.search(r"c:(\d+)", line)
    return in_ms(int(m.group(1))) if m else 0

lines = [l.rstrip("\r\n") for l in open(path) if l.strip()]
lines = [jittered(l) for l in lines]
with open(path, "w") as full, open(path[: -len(".nmea")] + "-lossy.nmea", "w") as lossy:
    for k in range(len(lines) // 3):  # three lines per sample: ROT, RSA, VBW
        # in the order of their (jittered) times, as they would arrive
        rows = "".join(l + "\n" for l in sorted(lines[3 * k : 3 * k + 3], key=tag_time))
        full.write(rows)
        if k % every != every - 1:
            lossy.write(rows)
EOF
        for in in "$f" "$f-lossy"; do
          for h in max-age due; do
            "$exe" replay --config "$here/config/vessels/$v.yaml" --input "$in.nmea" \
              --nmea-hold "$h" --output "$in-$h.jsonl" 2>/dev/null
          done
        done
      done
    done
  done
done

python3 - "$work" "$every" "$noise" "$jitter" "$rsa_phase" <<'EOF'
import glob, json, os, sys

work, every, noises, jitter, rsa_phase = sys.argv[1], sys.argv[2], sys.argv[3].split(), sys.argv[4], sys.argv[5]

def raised(path):
    out = []
    with open(path) as f:
        for line in f:
            e = json.loads(line)
            if e.get("type") == "event" and e.get("state") == "raised":
                out.append((e["sensor"], e["stamp"]))
    return out

def unmatched(a, b, tol=5.0):
    return [x for x in a if not any(x[0] == y[0] and abs(x[1] - y[1]) <= tol for y in b)]

print(f"every {every}th datagram lost, TAG times +-{jitter} ms, RSA {rsa_phase} ms later; raised events summed over the runs\n")
print("| noise scale | hold | runs | raised, lossless | raised, lossy | invented | lost |")
print("|---|---|---|---|---|---|---|")
for ns in noises:
    bases = sorted(p[: -len("-due.jsonl")] for p in glob.glob(os.path.join(work, f"ns{ns}-*-due.jsonl"))
                   if not p.endswith("-lossy-due.jsonl"))
    for hold in ("max-age", "due"):
        n_ll = n_ly = inv = lost = 0
        for b in bases:
            ll = raised(f"{b}-{hold}.jsonl")
            ly = raised(f"{b}-lossy-{hold}.jsonl")
            n_ll += len(ll)
            n_ly += len(ly)
            inv += len(unmatched(ly, ll))
            lost += len(unmatched(ll, ly))
        print(f"| {ns} | {hold} | {len(bases)} | {n_ll} | {n_ly} | {inv} | {lost} |")
EOF
