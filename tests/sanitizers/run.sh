#!/usr/bin/env bash
# The unit tests once more, built with AddressSanitizer + UndefinedBehaviorSanitizer
# (build-asan/): any invalid access, leak or undefined behaviour fails the run.
#   tests/sanitizers/run.sh [BUILD_DIR]
# The window tests are left out: SDL's X11 driver leaks from a library it has unloaded,
# which LeakSanitizer cannot name, so no suppression can target it.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build-asan}
# A unity build, as setup.sh's (5.3 minutes to build). Warnings are the normal build's job
# (-Werror there); the instrumentation confuses them.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DTESSERA_SANITIZE=ON -DTESSERA_WERROR=OFF \
  -DCMAKE_UNITY_BUILD=ON >/dev/null
cmake --build "$build" -j"$(nproc)" --target common_tests renderer_tests compositor_tests display_tests \
  master_tests launcher_tests
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizers/lsan.supp"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
ctest --test-dir "$build" -L unit -E WindowSinkXvfb --output-on-failure -j2 --timeout 600
