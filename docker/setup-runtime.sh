#!/usr/bin/env bash
# Runtime-stage set-up of docker/Dockerfile: the unprivileged system user the sidecar runs as and
# the directories it uses, owned by it:
#   /etc/usv-fdi       configuration mounted or baked in (vessel YAML, security profiles)
#   /run/usv-fdi       health file (usv-fdi run --health-file), tmpfs in docker/compose.yaml
#   /var/lib/usv-fdi   persistent state (event journal / Fast DDS persistence), a volume
#
#   docker/setup-runtime.sh [ROOT]   ROOT: apply to another root directory (default /), using
#                                    useradd --prefix; lets the script be checked outside a build
set -euo pipefail
root="${1:-/}"
root="${root%/}"
user=usv-fdi
id=10001
[ -d "$root/etc" ] || { echo "setup-runtime: $root/etc missing" >&2; exit 2; }
prefix=()
[ -z "$root" ] || prefix=(--prefix "$root")
if ! grep -q "^$user:" "$root/etc/group"; then
  groupadd "${prefix[@]}" --gid "$id" "$user"
fi
if ! grep -q "^$user:" "$root/etc/passwd"; then
  useradd "${prefix[@]}" --uid "$id" --gid "$id" --no-create-home \
    --home-dir /var/lib/usv-fdi --shell /usr/sbin/nologin "$user"
fi
install -d -m 0755 "$root/etc/usv-fdi"
install -d -m 0750 -o "$id" -g "$id" "$root/run/usv-fdi" "$root/var/lib/usv-fdi"
echo "setup-runtime: user $user ($id), /etc/usv-fdi, /run/usv-fdi, /var/lib/usv-fdi in ${root:-/}"
