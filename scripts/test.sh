#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test (./build);
# then builds the DDS service's tests under ThreadSanitizer (./build-tsan) and
# AddressSanitizer + UBSan (./build-asan) and runs them: the pipeline's threading tests, the
# sidecar in-process behind real Fast DDS, and the end-to-end tests of the instrumented
# usv-fdi executable in separate processes; under ASan + UBSan also the golden replays (the
# engine itself).
#
#   USV_FDI_SANITIZERS="thread address"  (default) which sanitizer builds to run; "" for none
#   BUILD_DIR=build                      the main build directory
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
"$root/scripts/build.sh" -DUSV_FDI_BUILD_TESTS=ON -DUSV_FDI_BUILD_BENCH=ON
failed=()  # test runs that failed: every run goes ahead, the script fails at the end
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j 2 --timeout 1500 ||
  failed+=("${BUILD_DIR:-build}")

# Only what the service's tests need is built with a sanitizer (Fast DDS itself is not
# instrumented; see tests/sanitizers/ for the runtime options and suppressions).
san_targets=(usv_fdi_pipeline_tests usv_fdi_service_tests usv_fdi_service_e2e_tests
             usv_fdi_nmea_udp_e2e_tests usv_fdi_ros2_e2e_tests usv-fdi)
for san in ${USV_FDI_SANITIZERS-thread address}; do
  case "$san" in
    thread) dir=build-tsan ;;
    address) dir=build-asan ;;
    *) echo "test.sh: unknown sanitizer '$san' in USV_FDI_SANITIZERS (thread, address)" >&2; exit 2 ;;
  esac
  echo "== $san sanitizer: $dir"
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DUSV_FDI_SANITIZER="$san" \
    -DUSV_FDI_BUILD_TESTS=ON -DUSV_FDI_BUILD_BENCH=OFF
  cmake --build "$dir" -j "$(nproc)" --target "${san_targets[@]}"
  ctest --test-dir "$dir" -L 'service|dds_e2e' --output-on-failure -j 2 --timeout 600 ||
    failed+=("$dir")
  if [[ "$san" == address ]]; then
    # The engine itself, single-threaded, under ASan + UBSan: the golden replays (usv-fdi
    # replay of every committed case, its output diffed exactly).
    ctest --test-dir "$dir" -R '^golden_output_' --output-on-failure -j 2 --timeout 600 ||
      failed+=("$dir (golden)")
  fi
done
if ((${#failed[@]} > 0)); then
  echo "test.sh: tests failed in: ${failed[*]}" >&2
  exit 1
fi
echo "test.sh: all tests passed"
