#!/usr/bin/env bash
# Build stage of docker/Dockerfile (also runnable on any bookworm machine with the [build]
# packages): configures and builds usv-fdi from SRC and stages what the runtime image ships into
# STAGE, laid out as the image's root:
#   STAGE/usr/local/bin/usv-fdi                  the executable (stripped)
#   STAGE/usr/local/share/usv-fdi/config/...     config/ (engine, vessel, QoS, security templates)
# then checks that every shared library usv-fdi needs comes from a package in the [runtime]
# section of scripts/packages.txt (docker/check-runtime-libs.sh).
#
#   docker/build.sh SRC STAGE [BUILD_DIR]
#   USV_FDI_TESTS=ON   also install the [test] packages, build and run the test suite (ctest)
#                      before staging
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: docker/build.sh SRC STAGE [BUILD_DIR]" >&2; exit 2; }
src="$(cd "$1" && pwd)"
stage="$2"
build="${3:-$src/build-docker}"
tests="${USV_FDI_TESTS:-OFF}"
case "$tests" in ON | OFF) ;; *) echo "docker/build.sh: USV_FDI_TESTS must be ON or OFF" >&2; exit 2 ;; esac

if [ "$tests" = ON ]; then "$src/scripts/install-deps.sh" --only test; fi
# The dashboard's chart library comes from npm at build time ([web] in scripts/packages.txt);
# the image's build stage has no npm unless the tests brought it: a vessel page without charts.
charts=OFF
if command -v npm > /dev/null 2>&1; then charts=ON; fi
cmake -S "$src" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DUSV_FDI_WITH_DDS=ON -DUSV_FDI_BUILD_TESTS="$tests" -DUSV_FDI_BUILD_BENCH=OFF \
  -DUSV_FDI_DASHBOARD_CHARTS="$charts"
if [ "$tests" = ON ]; then
  cmake --build "$build" -j "$(nproc)"
  ctest --test-dir "$build" --output-on-failure -j "$(nproc)" --timeout 1500
else
  cmake --build "$build" -j "$(nproc)" --target usv-fdi
fi

rm -rf "$stage"
install -d "$stage/usr/local/bin" "$stage/usr/local/share/usv-fdi"
install -m 0755 -s "$build/usv-fdi" "$stage/usr/local/bin/usv-fdi"
cp -R "$src/config" "$stage/usr/local/share/usv-fdi/config"
cp "$src/docker/fleet_participants.xml" "$stage/usr/local/share/usv-fdi/config/qos/"
chmod -R a+rX,go-w "$stage/usr/local/share/usv-fdi"
"$src/docker/check-runtime-libs.sh" "$stage/usr/local/bin/usv-fdi"
"$stage/usr/local/bin/usv-fdi" --help >/dev/null
echo "docker/build.sh: staged $(du -sh "$stage" | cut -f1) in $stage"
