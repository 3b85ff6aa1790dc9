#!/usr/bin/env bash
# Regenerates the golden replay files under tests/golden (inputs made by `usv-fdi sim`,
# expected outputs of `usv-fdi replay`; tests/golden/cases.txt lists the cases), after
# building usv-fdi. Deterministic: running it twice gives the same files. Review the diff
# (git diff tests/golden) and commit it with the change that caused it.
#
#   ./scripts/update-golden.sh                 regenerate inputs and outputs
#   ./scripts/update-golden.sh --outputs-only  keep the committed inputs, replay them again
#
# BUILD_DIR (default: build) selects the build tree; it is configured with
# ./scripts/build.sh when it does not exist yet.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build_dir="${BUILD_DIR:-build}"
case "${1:-}" in
  "" | --outputs-only) ;;
  *)
    sed -n '2,12p' "${BASH_SOURCE[0]}" >&2
    exit 2
    ;;
esac
if [ -f "$build_dir/CMakeCache.txt" ]; then
  cmake --build "$build_dir" --target usv-fdi
else
  BUILD_DIR="$build_dir" "$root/scripts/build.sh"
fi
exec "$root/tests/golden/golden.sh" update "$build_dir/usv-fdi" "$@"
