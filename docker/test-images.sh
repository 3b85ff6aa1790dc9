#!/usr/bin/env bash
# Builds every target of docker/Dockerfile and runs what the images ship, as a user deploys them
# (issue 14, "Containers, built and run for real"). There is no Docker engine here: Debian's
# podman builds the Dockerfile as it is and buildah runs the images' programs, both with chroot
# isolation (no cgroups, no network namespace: the programs use the host's loopback).
#
#   1. Base image: a Debian bookworm made with debootstrap from this machine's apt sources and
#      imported with `podman import` as localhost/usv-fdi-base:bookworm (made once, reused by
#      later runs; USV_FDI_BASE_IMAGE=NAME uses another bookworm image instead).
#   2. `podman build --format docker` of the targets runtime (with build and runtime-base) and
#      discovery; docker format, so that the image keeps its HEALTHCHECK.
#   3. The runtime image's configuration: user usv-fdi (10001), working directory, entrypoint,
#      command, environment and health check, read back with `podman image inspect`.
#   4. The discovery image's server (its entrypoint and command; only the port changed) and the
#      runtime image's sidecar (its entrypoint and default command, under its own user, with a
#      vessel configuration mounted at /etc/usv-fdi/vessel.yaml as docker/README.md says) run
#      with `buildah run`; a simulator on the host publishes the paper's scenario through that
#      server; a monitor on the host must see the sidecar raise the gyro's and then the
#      accelerometer's fault, each isolated to its sensor. The image's health check command
#      passes while the sidecar runs and fails once it has stopped.
#
#   docker/test-images.sh USV_FDI_EXE     (the host's usv-fdi: simulator and monitor)
#
# Needs root, podman, buildah and debootstrap ([container] in scripts/packages.txt); exits 77 (ctest:
# skipped) with the reason where one is missing. Logs and the build output stay in a temporary
# directory when the test fails. Every container it makes is removed at exit.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
src="$(cd "$here/.." && pwd)"
[ $# -eq 1 ] || { echo "usage: docker/test-images.sh USV_FDI_EXE" >&2; exit 2; }
exe="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
[ -x "$exe" ] || { echo "test-images: $1 is not an executable" >&2; exit 2; }

skip() { echo "SKIP: $*"; exit 77; }
[ "$(id -u)" -eq 0 ] || skip "needs root (podman and buildah with chroot isolation, debootstrap)"
for tool in podman buildah debootstrap python3; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (scripts/install-deps.sh --only container)"
done
for tool in ss pgrep ps; do  # iproute2, procps ([test] in scripts/packages.txt)
  command -v "$tool" >/dev/null || skip "$tool is not installed (scripts/install-deps.sh --only test)"
done

work="$(mktemp -d /tmp/usv-fdi-images.XXXXXX)"
containers=()
pids=()  # `buildah run` clients still running
ok=0
descendants() {  # PID -> every process below it
  local c
  for c in $(pgrep -P "$1"); do echo "$c"; descendants "$c"; done
}
# Stops a `buildah run` and what runs in it: the program runs as another user, so it does not
# die with the client; TERM to all, then KILL to what is left after 5 s.
stop_run() {  # PID
  local all p
  all="$(descendants "$1") $1"
  for p in $all; do kill -TERM "$p" 2>/dev/null || true; done
  for _ in $(seq 1 50); do
    kill -0 "$1" 2>/dev/null || break
    sleep 0.1
  done
  for p in $all; do kill -KILL "$p" 2>/dev/null || true; done
  wait "$1" 2>/dev/null || true
}
forget() {  # PID: waited for, no longer to be stopped at exit
  local keep=() p
  for p in "${pids[@]}"; do [ "$p" = "$1" ] || keep+=("$p"); done
  pids=("${keep[@]}")
}
cleanup() {
  for p in "${pids[@]}"; do stop_run "$p"; done
  for c in "${containers[@]}"; do buildah rm "$c" >/dev/null 2>&1 || true; done
  if [ "$ok" = 1 ]; then rm -rf "$work"; else echo "test-images: logs kept in $work" >&2; fi
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  for f in "$work"/*.log; do
    [ -e "$f" ] || continue
    echo "---- $(basename "$f") (last 40 lines)" >&2
    tail -n 40 "$f" >&2
  done
  exit 1
}
step_t0=$SECONDS
step() { echo "== [$((SECONDS - step_t0)) s] $*"; }

# ---- 1. the base image --------------------------------------------------------------------
base="${USV_FDI_BASE_IMAGE:-localhost/usv-fdi-base:bookworm}"
if ! podman image exists "$base"; then
  [ -z "${USV_FDI_BASE_IMAGE:-}" ] || fail "USV_FDI_BASE_IMAGE=$base: no such image"
  # The archive this machine's apt uses (deb822 sources or sources.list), so that the base
  # comes from where the machine's own packages come from.
  mirror="$(python3 - <<'EOF'
import glob, re
uris = []
for path in sorted(glob.glob("/etc/apt/sources.list.d/*.sources")):
    text = open(path, encoding="utf-8", errors="replace").read()
    for stanza in re.split(r"\n\s*\n", text):
        fields = dict(re.findall(r"^(\w[\w-]*):\s*(.*)$", stanza, re.M))
        if "bookworm" in fields.get("Suites", "").split() and fields.get("Enabled", "yes") != "no":
            uris += fields.get("URIs", "").split()
for path in ["/etc/apt/sources.list"] + sorted(glob.glob("/etc/apt/sources.list.d/*.list")):
    try:
        for line in open(path, encoding="utf-8", errors="replace"):
            m = re.match(r"\s*deb\s+(?:\[[^]]*\]\s+)?(\S+)\s+bookworm\s", line)
            if m:
                uris.append(m.group(1))
    except OSError:
        pass
print(uris[0] if uris else "")
EOF
)"
  [ -n "$mirror" ] || skip "no apt source for bookworm in /etc/apt: debootstrap needs an archive"
  step "debootstrap bookworm (minbase) from $mirror"
  debootstrap --variant=minbase bookworm "$work/rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 ||
    fail "debootstrap bookworm from $mirror (see debootstrap.log)"
  tar -C "$work/rootfs" -c . | podman import - "$base" >"$work/import.log" 2>&1 ||
    fail "podman import of the debootstrap root"
  rm -rf "$work/rootfs"
fi

# ---- 2. every target of the Dockerfile ----------------------------------------------------
tag="localhost/usv-fdi-test"
build_target() {  # TARGET IMAGE
  step "podman build --target $1 -> $2"
  podman build --isolation chroot --format docker --layers \
    --ignorefile "$src/docker/Dockerfile.dockerignore" --build-arg "DEBIAN_IMAGE=$base" \
    --target "$1" -f "$src/docker/Dockerfile" -t "$2" "$src" >"$work/build-$1.log" 2>&1 ||
    fail "podman build --target $1 (see build-$1.log)"
}
build_target runtime "$tag:runtime"  # its stages: build, runtime-base, runtime
build_target discovery "$tag:discovery"

# ---- 3. the runtime image's configuration -------------------------------------------------
inspect() { podman image inspect "$1"; }
inspect "$tag:runtime" >"$work/runtime-config.json"
inspect "$tag:discovery" >"$work/discovery-config.json"
# One line per fact, checked below, and the commands as NUL-free shell words.
python3 - "$work" <<'EOF' || fail "the images' configuration (above)"
import json, shlex, sys
work = sys.argv[1]
rt_image = json.load(open(work + "/runtime-config.json"))[0]
rt, ds = rt_image["Config"], json.load(open(work + "/discovery-config.json"))[0]["Config"]
errors = []
def expect(what, got, want):
    if got != want:
        errors.append(f"{what}: {got!r}, expected {want!r}")
expect("runtime User", rt.get("User"), "usv-fdi")
expect("runtime WorkingDir", rt.get("WorkingDir"), "/var/lib/usv-fdi")
expect("runtime Entrypoint", rt.get("Entrypoint"), ["usv-fdi"])
cmd = rt.get("Cmd") or []
expect("runtime Cmd[0]", cmd[:1], ["run"])
if "/etc/usv-fdi/vessel.yaml" not in cmd:
    errors.append(f"runtime Cmd {cmd!r} does not read /etc/usv-fdi/vessel.yaml")
env = dict(e.split("=", 1) for e in rt.get("Env") or [])
for key in ("USV_FDI_QOS_PROFILES", "FASTRTPS_DEFAULT_PROFILES_FILE"):
    if not env.get(key, "").startswith("/usr/local/share/usv-fdi/config/qos/"):
        errors.append(f"runtime Env {key} = {env.get(key)!r}")
# podman keeps a docker-format image's HEALTHCHECK beside its Config
hc = (rt_image.get("Healthcheck") or rt.get("Healthcheck") or {}).get("Test") or []
expect("runtime Healthcheck kind", hc[:1], ["CMD"])
expect("runtime Healthcheck command", hc[1:3], ["usv-fdi", "health"])
expect("discovery User", ds.get("User"), "usv-fdi")
expect("discovery Entrypoint", ds.get("Entrypoint"), ["fastdds", "discovery"])
dcmd = ds.get("Cmd") or []
if "--port" not in dcmd:
    errors.append(f"discovery Cmd {dcmd!r} has no --port")
for e in errors:
    print("FAIL:", e, file=sys.stderr)
if errors:
    sys.exit(1)
with open(work + "/commands.sh", "w") as f:
    f.write("runtime_cmd=(" + " ".join(map(shlex.quote, rt["Entrypoint"] + cmd)) + ")\n")
    f.write("health_cmd=(" + " ".join(map(shlex.quote, hc[1:])) + ")\n")
    f.write("discovery_cmd=(" + " ".join(map(shlex.quote, ds["Entrypoint"] + dcmd)) + ")\n")
EOF
runtime_cmd=() health_cmd=() discovery_cmd=()
# shellcheck disable=SC1091
source "$work/commands.sh"
echo "runtime: ${runtime_cmd[*]}"
echo "health check: ${health_cmd[*]}"

# ---- 4. run them ----------------------------------------------------------------------------
# A UDP port nobody listens on, for the discovery server (the image's command, port changed).
port=""
for _ in $(seq 1 50); do
  p=$((20000 + RANDOM % 20000))
  if ! ss -Hlun "sport = :$p" | grep -q .; then port=$p; break; fi
done
[ -n "$port" ] || fail "no free UDP port for the discovery server"
for i in "${!discovery_cmd[@]}"; do
  if [ "${discovery_cmd[i]}" = "--port" ]; then discovery_cmd[i + 1]="$port"; fi
done

# Working containers of the images (removed at exit; made here, not in a subshell, so that
# the list the cleanup reads has them).
disc="$(buildah from --name "usv-fdi-test-discovery-$$" "$tag:discovery")" ||
  fail "buildah from $tag:discovery"
containers+=("$disc")
side="$(buildah from --name "usv-fdi-test-sidecar-$$" "$tag:runtime")" ||
  fail "buildah from $tag:runtime"
containers+=("$side")
# Every participant but the server is a client of it (as in docker/compose.yaml).
buildah config --env "ROS_DISCOVERY_SERVER=127.0.0.1:$port" "$side"

mmsi=257000091
mkdir -p "$work/etc" "$work/run"
{
  cat "$src/config/scenarios/paper.yaml"
  # UDP only: the host's simulator and the container do not share /dev/shm.
  printf '\nservice:\n  mmsi: %s\n  participant_profile: usv_fdi_fleet_udp\n' "$mmsi"
  printf '  reliable_inputs: true\n  input_timeout: 60\n  rudder_wait: 1.0\n'
} >"$work/etc/vessel.yaml"
chmod 0644 "$work/etc/vessel.yaml"
chown 10001:10001 "$work/run"  # the image's /run/usv-fdi belongs to usv-fdi (10001)
mounts=(-v "$work/etc/vessel.yaml:/etc/usv-fdi/vessel.yaml:ro" -v "$work/run:/run/usv-fdi")

step "discovery server: ${discovery_cmd[*]}"
buildah run --isolation chroot "$disc" -- "${discovery_cmd[@]}" >"$work/discovery.log" 2>&1 &
pids+=($!)
deadline=$((SECONDS + 30))
until ss -Hlun "sport = :$port" | grep -q .; do
  ((SECONDS < deadline)) || fail "the discovery image's server does not listen on UDP $port"
  sleep 0.2
done

step "sidecar: ${runtime_cmd[*]}"
buildah run --isolation chroot "${mounts[@]}" "$side" -- "${runtime_cmd[@]}" \
  >"$work/sidecar.log" 2>&1 &
sidecar_pid=$!
pids+=("$sidecar_pid")
deadline=$((SECONDS + 60))
until grep -q "waiting for INS and rudder" "$work/sidecar.log"; do
  kill -0 "$sidecar_pid" 2>/dev/null || fail "the image's sidecar exited before it was ready"
  ((SECONDS < deadline)) || fail "the image's sidecar not ready after 60 s"
  sleep 0.2
done
# The image's program itself (not buildah's helpers), and it runs as the image's user.
program=""
for p in $(descendants "$sidecar_pid"); do
  [ "$(ps -o comm= -p "$p")" = usv-fdi ] && program=$p
done
[ -n "$program" ] || fail "no usv-fdi process under the sidecar's buildah run ($sidecar_pid)"
owner="$(ps -o uid= -p "$program" | tr -d ' ')"
[ "$owner" = 10001 ] ||
  fail "the sidecar's process runs as uid '$owner', not as the image's user usv-fdi (10001)"

host_env=(env "FASTRTPS_DEFAULT_PROFILES_FILE=$src/docker/fleet_participants.xml"
  "ROS_DISCOVERY_SERVER=127.0.0.1:$port")
host_dds=(--qos "$src/config/qos/usv_fdi_profiles.xml" --participant-profile usv_fdi_fleet_udp)

step "monitor on the host (live), then the simulator: the paper's scenario at 5x real time"
"${host_env[@]}" "$exe" monitor --json --mmsi "$mmsi" "${host_dds[@]}" \
  >"$work/monitor.json" 2>"$work/monitor.log" &
monitor_pid=$!
pids+=("$monitor_pid")
"${host_env[@]}" "$exe" sim --publish --vessel otter --scenario paper --noise-scale 0 \
  --speed 5 --reliable --wait-readers 60 --linger 2 --mmsi "$mmsi" "${host_dds[@]}" \
  >"$work/sim.log" 2>&1 || fail "the host's simulator (see sim.log)"

step "health check while the sidecar runs: ${health_cmd[*]}"
buildah run --isolation chroot "${mounts[@]}" "$side" -- "${health_cmd[@]}" \
  >"$work/health-running.log" 2>&1 || fail "the image's health check fails on a running sidecar"
grep -q "^healthy" "$work/health-running.log" || fail "health check output (health-running.log)"

# Both raises reach the monitor (bounded wait: the sim has ended, the events are latched).
deadline=$((SECONDS + 30))
until [ "$(grep -c '"state":"raised"' "$work/monitor.json")" -ge 2 ]; do
  ((SECONDS < deadline)) || break
  sleep 0.5
done
kill -TERM "$monitor_pid" 2>/dev/null || true
wait "$monitor_pid" 2>/dev/null || true
forget "$monitor_pid"
python3 - "$work/monitor.json" "$mmsi" <<'PY' || fail "the monitor's view (monitor.json above)"
import json, sys
path, mmsi = sys.argv[1], int(sys.argv[2])
raises = {}
for line in open(path):
    if not line.startswith("{"):
        continue
    r = json.loads(line)
    if r.get("type") == "fault" and r.get("mmsi") == mmsi and r.get("state") == "raised":
        raises.setdefault(r["sensor"], r)  # the first raise of each sensor
errors = []
for sensor, own, other in (("gyro", "c_g", "c_a"), ("accelerometer", "c_a", "c_g")):
    e = raises.get(sensor)
    if e is None:
        errors.append(f"no raise of the {sensor} from vessel {mmsi}")
    elif not e[own] > e[other]:
        errors.append(f"{sensor}: not isolated to it ({own} {e[own]}, {other} {e[other]})")
    else:
        print(f"{sensor}: raised, {e['kind']}, onset {e['onset_time']} s, {own} {e[own]:.2f}")
if set(raises) - {"gyro", "accelerometer"}:
    errors.append(f"raises of {sorted(set(raises) - {'gyro', 'accelerometer'})} as well")
if not errors and not raises["gyro"]["onset_time"] < raises["accelerometer"]["onset_time"]:
    errors.append("the gyro's fault (20-40 s) not raised before the accelerometer's (60-80 s)")
for e in errors:
    print("FAIL:", e, file=sys.stderr)
if errors:
    print(open(path).read(), file=sys.stderr)
sys.exit(1 if errors else 0)
PY

# As `docker stop` does: SIGTERM to the container's program itself (buildah run does not pass
# a signal on to it), which must then stop cleanly and leave a health file that says so.
step "stop the sidecar (SIGTERM to the image's usv-fdi); the health check must fail"
kill -TERM "$program"
deadline=$((SECONDS + 30))
while kill -0 "$sidecar_pid" 2>/dev/null; do
  ((SECONDS < deadline)) || fail "the image's sidecar did not stop within 30 s of SIGTERM"
  sleep 0.2
done
rc=0
wait "$sidecar_pid" || rc=$?
forget "$sidecar_pid"
[ "$rc" = 0 ] || fail "the image's sidecar exited with status $rc after SIGTERM (see sidecar.log)"
if buildah run --isolation chroot "${mounts[@]}" "$side" -- "${health_cmd[@]}" \
  >"$work/health-stopped.log" 2>&1; then
  fail "the image's health check passes after the sidecar stopped: $(cat "$work/health-stopped.log")"
fi
grep -q "stopped" "$work/health-stopped.log" ||
  fail "the health check after the stop does not say the sidecar stopped (health-stopped.log)"
echo "health check after the stop: $(cat "$work/health-stopped.log")"
ok=1
step "ok: runtime and discovery images built; the image's sidecar raised and isolated both faults"
