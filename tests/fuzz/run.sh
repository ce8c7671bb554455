#!/usr/bin/env bash
# Builds the libFuzzer targets with clang in a separate build dir and runs each one for a
# bounded time. Exits non-zero on any crash, leak or sanitizer report (reproducer saved
# under $BUILD/fuzz-artifacts). Usage: tests/fuzz/run.sh [seconds per target, default 20]
# Env: BUILD=<dir> (default <repo>/build-fuzz).
set -euo pipefail
SRC=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$SRC/build-fuzz}
SECS=${1:-20}
command -v clang++ >/dev/null || { echo "clang++ not found: apt-get install clang" >&2; exit 2; }
cmake -S "$SRC" -B "$BUILD" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DTESSERA_FUZZ=ON >/dev/null
cmake --build "$BUILD" --target protocol_fuzz strips_fuzz -j2
mkdir -p "$BUILD/fuzz-artifacts"
for t in protocol_fuzz strips_fuzz; do
  corpus="$BUILD/fuzz-corpus/$t"
  mkdir -p "$corpus"
  log="$BUILD/fuzz-artifacts/$t.log"
  echo "== $t for ${SECS}s (corpus $corpus, log $log)"
  if ! TESSERA_FUZZ_SEEDS="$corpus" "$BUILD/bin/$t" -max_total_time="$SECS" -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$BUILD/fuzz-artifacts/$t-" "$corpus" >"$log" 2>&1; then
    tail -40 "$log" >&2
    echo "$t FAILED: reproducer in $BUILD/fuzz-artifacts" >&2
    exit 1
  fi
  grep -E "^#[0-9]+ +DONE|number_of_executed_units|new_units_added" "$log" || true
done
echo "fuzz: all targets ran clean"
