#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) into ${FUZZ_BUILD_DIR:-build-fuzz} and runs
# each for a bounded time. Exits non-zero on the first crash, sanitizer report, leak, timeout or
# out-of-memory; the reproducer is left in <build>/fuzz/artifacts/<target>/ and its path printed.
#
#   scripts/fuzz.sh [TARGET...]        TARGET: config, csv, engine, nmea (default: all four)
#   FUZZ_SECONDS=60   time per target (libFuzzer -max_total_time)
#   FUZZ_JOBS=1       parallel fuzzing processes per target (-fork=N when > 1)
#   FUZZ_ARGS=...     extra libFuzzer flags (e.g. -seed=1 -runs=100000)
#
# The committed seeds (tests/fuzz/corpus/<target>) are only read: every run works on a copy in the
# build directory, so what the fuzzer discovers never dirties the tree. A crash input worth keeping
# goes to tests/io as a regression test, not into the corpus.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
"$root/scripts/install-deps.sh"

seconds="${FUZZ_SECONDS:-60}"
jobs="${FUZZ_JOBS:-1}"
build_dir="${FUZZ_BUILD_DIR:-build-fuzz}"
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(config csv engine nmea)
for t in "${targets[@]}"; do
  case "$t" in
    config | csv | engine | nmea) ;;
    *) echo "fuzz.sh: unknown target '$t' (expected config, csv, engine or nmea)" >&2; exit 2 ;;
  esac
done
case "$seconds" in
  '' | *[!0-9]*) echo "fuzz.sh: FUZZ_SECONDS must be a whole number of seconds, not '$seconds'" >&2; exit 2 ;;
esac

cxx="$(command -v clang++-14 || command -v clang++ || true)"
cc="$(command -v clang-14 || command -v clang || true)"
if [ -z "$cxx" ]; then
  echo "fuzz.sh: clang++ not found (scripts/packages.txt lists clang-14)" >&2
  exit 2
fi
launcher=()
if command -v ccache >/dev/null 2>&1; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_C_COMPILER="$cc" "${launcher[@]}" \
  -DUSV_FDI_FUZZ=ON -DUSV_FDI_WITH_DDS=OFF -DUSV_FDI_BUILD_TESTS=OFF -DUSV_FDI_BUILD_BENCH=OFF >/dev/null
cmake --build "$build_dir" -j "$(nproc)" --target $(printf 'usv_fdi_fuzz_%s ' "${targets[@]}")

export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1:allocator_may_return_null=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
status=0
for t in "${targets[@]}"; do
  work="$build_dir/fuzz/work/$t"
  artifacts="$build_dir/fuzz/artifacts/$t"
  rm -rf "$work"
  mkdir -p "$work" "$artifacts"
  cp tests/fuzz/corpus/"$t"/* "$work"/
  fork=()
  if [ "$jobs" -gt 1 ]; then fork=(-fork="$jobs" -ignore_crashes=0); fi
  echo "== fuzz $t: ${seconds}s, seeds $(ls tests/fuzz/corpus/"$t" | wc -l), artifacts in $artifacts"
  log="$build_dir/fuzz/$t.log"
  # -timeout: one input taking > 10 s is a hang; -rss_limit_mb: > 2 GB is a memory bomb.
  # shellcheck disable=SC2086
  if "$build_dir/fuzz/usv_fdi_fuzz_$t" "$work" -dict="tests/fuzz/$t.dict" \
      -max_total_time="$seconds" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
      -artifact_prefix="$artifacts/" -print_final_stats=1 "${fork[@]}" ${FUZZ_ARGS:-} \
      >"$log" 2>&1; then
    grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)|^#[0-9]+ *DONE' "$log" || true
    echo "== fuzz $t: no crash (corpus now $(ls "$work" | wc -l) inputs)"
  else
    status=1
    tail -n 60 "$log"
    echo "== fuzz $t: FAILED; reproducer(s):" >&2
    ls -1 "$artifacts" >&2
    echo "   rerun one with: $build_dir/fuzz/usv_fdi_fuzz_$t <file>" >&2
  fi
done
exit "$status"
