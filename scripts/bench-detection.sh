#!/usr/bin/env bash
# The detection benchmark of the proving ground (docs/benchmark.md).
#
#   scripts/bench-detection.sh [--quick] [--jobs N] [--json FILE] [--markdown FILE] [...]
#
# Builds build/usv-fdi-bench-detection (configuring ./build with the benchmarks on if it is
# not there yet) and runs it with the arguments given; `--help` lists them. The full mode
# runs for hours on 2 cores: run it under `nice`, with --jobs matching the free cores.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${USV_FDI_BUILD_DIR:-$here/build}"
if [[ ! -f "$build/build.ninja" && ! -f "$build/Makefile" ]]; then
  cmake -S "$here" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DUSV_FDI_BUILD_BENCH=ON
fi
cmake --build "$build" --target usv-fdi-bench-detection -j "${USV_FDI_BUILD_JOBS:-2}" >&2
exec "$build/usv-fdi-bench-detection" "$@"
