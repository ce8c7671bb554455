#!/usr/bin/env bash
# Sets up Tessera on Debian 12: installs the packages the build needs, and for `test` those
# the tests and benchmarks need (idempotent; as root, or with sudo), builds into build/, then:
#   ./setup.sh          set up and build only
#   ./setup.sh run      ... and run the farm (compose.yaml) on the built-in default scene
#   ./setup.sh test     ... and run every test (ctest, fuzzers for a bounded time, compose check,
#                       the unit tests again under ASan + UBSan)
#   ./setup.sh deps     install what building and running need, and nothing else (the Docker image)
# Only `test` installs the test tools (clang, Xvfb, chromium, a one-host Slurm, docker-compose...):
# running the farm on a workstation does not put Slurm daemons on it.
set -euo pipefail
CALLER_DIR=$PWD  # `run` starts the farm from here: TESSERA_SCENE/TESSERA_OUT are the user's paths
cd "$(dirname "$0")"
REPO=$PWD
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
PKGS=(
  build-essential cmake pkg-config ninja-build
  libzmq3-dev cppzmq-dev liblzo2-dev libdeflate-dev liblz4-dev libzstd-dev
  libosmesa6-dev libspdlog-dev libfmt-dev libyaml-cpp-dev libcli11-dev
  libpng-dev libisal-dev libsdl2-dev nlohmann-json3-dev libfftw3-dev zlib1g-dev libnifti2-dev libgdcm-dev libgdcm-tools libtiff-dev
  libgtest-dev libgmock-dev libbenchmark-dev libteem-dev libxtst-dev
  libcivetweb-dev libturbojpeg0-dev libwebsockets-dev
)
# optional: python3-vtk9 python3-yaml for tests/bench/vtk_compare.py
# Tests, fuzzing, benchmarks' plots, the window test under Xvfb, compose validation, the
# one-host Slurm cluster of the Slurm tests. libclang-rt-14-dev holds the fuzzers' runtimes
# (libFuzzer, ASan, UBSan): clang only recommends it, and recommends are not installed.
mode=${1:-build}
[ "$mode" != test ] || PKGS+=(gnuplot-nox xvfb x11-apps imagemagick clang libclang-rt-14-dev docker-compose procps iproute2
  slurmctld slurmd slurm-client munge chromium curl)
missing=()
for p in "${PKGS[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
# Node.js drives chromium in the web view's tests: Debian's, unless one is installed already.
if [ "$mode" = test ] && ! command -v npm >/dev/null; then missing+=(nodejs npm); fi
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

[ "$mode" = deps ] && exit 0
BUILD=${BUILD:-build}
werror=OFF
[ "${CI:-}" = true ] || [ "$mode" = test ] && werror=ON
# Unity build: each target's sources compiled in batches of 8, so the heavy headers (CLI11
# alone ~9 s a file at -O3) are compiled once a batch; a fresh build took 5.0 minutes instead
# of 7.7 on 2 cores. For editing, configure a build of your own without it (faster rebuilds).
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTESSERA_WERROR=$werror -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build "$BUILD" -j"$(nproc)"

case "$mode" in
  build) echo "built: $BUILD/bin" ;;
  run)
    shift || true
    # With a display, the farm is steered from its window (TESSERA_FRAMES=-1 plays the orbit instead).
    if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ -z "${TESSERA_FRAMES:-}" ]; then
      export TESSERA_FRAMES=0
      echo "running the farm on ${TESSERA_SCENE:-the built-in scene} in a window: drag to orbit, wheel to zoom, h for help, Esc to stop"
    else
      echo "running the farm on ${TESSERA_SCENE:-the built-in scene} (frames -> ${TESSERA_OUT:-out}/)"
    fi
    case "$BUILD" in /*) bin=$BUILD/bin ;; *) bin=$REPO/$BUILD/bin ;; esac
    cd "$CALLER_DIR"
    exec "$bin/tessera-up" "$REPO/compose.yaml" "$@"
    ;;
  test)
    docker-compose -f compose.yaml config -q
    # Swarm reads the file differently (no build, restart_policy): check it where the CLI is.
    if docker stack config --help >/dev/null 2>&1; then
      TESSERA_ENDPOINTS=tcp://master:5550 docker stack config -c compose.yaml >/dev/null
    else
      echo "docker stack config not available: Swarm check of compose.yaml skipped"
    fi
    # puppeteer-core for the web view's tests, pinned by tests/web/package-lock.json (it
    # drives Debian's chromium; no browser is downloaded).
    (cd tests/web && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
    tests/fuzz/run.sh "${TESSERA_FUZZ_SECONDS:-15}"
    ctest --test-dir "$BUILD" --output-on-failure -j2 --timeout 600
    tests/sanitizers/run.sh
    ;;
  *) echo "usage: $0 [build|run|test|deps]" >&2; exit 2 ;;
esac
