#!/usr/bin/env bash
# Time series on the farm: a generated float32 series (moving-blobs, SIZE^3, STEPS steps,
# written once by tessera-write-series as raw files) played at 1024x1024 by 2 and 4
# renderers, each run from a cold page cache (every step file dropped from it with
# dd iflag=nocache, i.e. posix_fadvise(POSIX_FADV_DONTNEED)). Per run: fps of the static
# volume (step 0 held) against playing forwards and backwards over FRAMES frames, the
# renderers' prefetch hit rate, file bytes read per renderer per step, the most a step
# cache held and the renderers' peak memory. Then memory over a LONG-frame loop (small
# image), and the first frame of a 10,000-step series against a 10-step one.
# Writes OUT/time-series.csv and prints Markdown tables. Runs anywhere; root is not needed.
# Every run turns the camera (an orbit), so every frame is rendered, static or playing.
# Usage: tests/bench/time_series_bench.sh [SIZE=256] [STEPS=100] [FRAMES=200] [LONG=1000] [OUT=bench-out/time] [BUILD=build]
# LONG=0 skips the long loop and the long series; RENDERERS="2" plays with 2 renderers only.
set -euo pipefail
SIZE=${1:-256}
STEPS=${2:-100}
FRAMES=${3:-200}
LONG=${4:-1000}
OUT=$(realpath -m "${5:-bench-out/time}")
BUILD=$(realpath "${6:-build}")
HERE=$(cd "$(dirname "$0")/../.." && pwd)
DATA="$OUT/data_${SIZE}_${STEPS}"
mkdir -p "$OUT"
[ -s "$DATA/step_$(printf %05d $((STEPS - 1))).raw" ] ||
  "$BUILD/bin/tessera-write-series" "$DATA" --size "$SIZE" --steps "$STEPS" --formats raw >/dev/null
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')

scene() {  # FILE TIME IMAGE FRAMES [DATA STEPS]
  local data=${5:-$DATA} steps=${6:-$STEPS}
  cat >"$1" <<EOF
volume:
  series: {pattern: $data/step_%05d.raw, first: 0, last: $((steps - 1))}
  dims: [$(sed -n 's/.*dims: \[\(.*\)\]/\1/p' "$data/series-raw.yaml")]
  type: $(sed -n 's/.*type: //p' "$data/series-raw.yaml")
  range: [0, 1]
transfer_function:
  - [0.0, 0.0, 0.0, 0.0, 0.0]
  - [0.2, 0.2, 0.5, 1.0, 0.1]
  - [1.0, 1.0, 0.8, 0.3, 0.9]
image: [$3, $3]
time: $2
orbit: {frames: $4}
EOF
}

cold() { for f in "$1"/step_*.raw; do dd if="$f" iflag=nocache count=0 status=none; done; }

# Runs the farm: NAME RENDERERS SCENE FRAMES; leaves OUT/NAME.log and OUT/NAME/metrics.jsonl.
farm() {
  TESSERA_RUN="ts$$$1" TESSERA_SCENE="$3" TESSERA_RENDERERS=$2 TESSERA_COMPOSITORS=1 TESSERA_FRAMES=$4 \
    TESSERA_OUT="$OUT/$1" TESSERA_WINDOW=off TESSERA_ENDPOINTS="ipc://$OUT/sockets_$1" \
    timeout 1800 "$BUILD/bin/tessera-up" "$HERE/compose.yaml" >"$OUT/$1.log" 2>&1 || { tail -20 "$OUT/$1.log"; exit 1; }
}

# fps (after the first 5 frames), hit rate, file bytes read per renderer per step over the
# first pass (every step new; MiB), most held by a step cache (MiB), largest renderer peak
# (MiB), first frame's done_ms.
summary() {  # NAME RENDERERS
  python3 - "$OUT/$1/metrics.jsonl" "$OUT/$1.log" "$2" "$STEPS" <<'EOF'
import json, re, sys
m = sorted((json.loads(l) for l in open(sys.argv[1])), key=lambda j: j["frame"])
log, n, steps = open(sys.argv[2]).read(), int(sys.argv[3]), int(sys.argv[4])
w = m[5:] if len(m) > 10 else m
fps = (len(w) - 1) * 1000.0 / (w[-1]["done_ms"] - w[0]["done_ms"]) if len(w) > 1 else 0
hits, misses = m[-1].get("render_step_hits", 0), m[-1].get("render_step_misses", 0)
rate = hits / (hits + misses) if hits + misses else float("nan")
first = m[:steps]
read = sum(j.get("render_bytes_read", 0) for j in first) / len(first) / n / 2**20
held = max([float(x) for x in re.findall(r"held at most ([0-9.]+) MiB", log)] or [0])
peak = max(float(x) for x in re.findall(r"renderer[^|\n]*\| [^\n]*peak memory ([0-9.]+) MiB", log))
print(f"{fps:.2f} {rate:.3f} {read:.1f} {held:.0f} {peak:.0f} {m[0]['done_ms']:.0f}")
EOF
}

step_mib=$(awk -v s="$SIZE" 'BEGIN { printf "%g", s * s * s * 4 / 1048576 }')
echo "config,renderers,size,steps,frames,fps,hit_rate,read_mib_per_renderer_step,cache_held_mib,renderer_peak_mib,first_frame_ms" >"$OUT/time-series.csv"
echo "## Playback vs a static volume: ${SIZE}^3 float32 (${step_mib} MiB a step), $STEPS steps, 1024x1024, cold cache ($cpu)"
echo
echo "| renderers | static fps | playing fps (ratio) | backwards fps (ratio) | prefetch hits fwd / back | read per renderer per step (its share) | cache held | renderer peak |"
echo "|---|---|---|---|---|---|---|---|"
for n in ${RENDERERS:-2 4}; do
  scene "$OUT/static.yaml" "{play: false}" 1024 60
  scene "$OUT/forward.yaml" "{play: true}" 1024 "$FRAMES"
  scene "$OUT/backward.yaml" "{play: true, stride: -1, step: $((STEPS - 1))}" 1024 "$FRAMES"
  declare -A r
  for c in static forward backward; do
    cold "$DATA"
    farm "${c}_$n" "$n" "$OUT/$c.yaml" "$([ $c = static ] && echo 60 || echo "$FRAMES")"
    r[$c]=$(summary "${c}_$n" "$n")
    echo "$c,$n,$SIZE,$STEPS,$FRAMES,${r[$c]// /,}" >>"$OUT/time-series.csv"
  done
  read -r sf _ _ _ _ _ <<<"${r[static]}"
  read -r ff fh fread fheld fpeak _ <<<"${r[forward]}"
  read -r bf bh _ _ bpeak _ <<<"${r[backward]}"
  awk -v n="$n" -v sf="$sf" -v ff="$ff" -v bf="$bf" -v fh="$fh" -v bh="$bh" -v rd="$fread" -v held="$fheld" \
    -v pk="$(( fpeak > bpeak ? fpeak : bpeak ))" -v share="$step_mib" 'BEGIN { printf "| %d | %.2f | %.2f (%.2f) | %.2f (%.2f) | %.1f%% / %.1f%% | %.1f MiB (%.2fx) | %d MiB | %d MiB |\n", n, sf, ff, ff / sf, bf, bf / sf, 100 * fh, 100 * bh, rd, rd / (share / n), held, pk }'
done

[ "$LONG" -gt 0 ] || exit 0
echo
echo "## Memory over a long loop: 2 renderers, 256x256, default cache budget"
echo
echo "| frames | renderer peak | cache held |"
echo "|---|---|---|"
for frames in $((LONG / 10)) "$LONG"; do
  scene "$OUT/long.yaml" "{play: true}" 256 "$frames"
  farm "long_$frames" 2 "$OUT/long.yaml" "$frames"
  read -r _ _ _ held peak _ <<<"$(summary "long_$frames" 2)"
  echo "long,2,$SIZE,$STEPS,$frames,,,,$held,$peak," >>"$OUT/time-series.csv"
  echo "| $frames | $peak MiB | $held MiB |"
done

echo
echo "## First frame of a long series: 32^3 uint16 steps, 2 renderers, 256x256"
echo
echo "| steps | first frame done (ms since the master started) |"
echo "|---|---|"
for steps in 10 10000; do
  d="$OUT/many_$steps"
  [ -s "$d/step_$(printf %05d $((steps - 1))).raw" ] ||
    "$BUILD/bin/tessera-write-series" "$d" --size 32 --steps "$steps" --type uint16 --formats raw >/dev/null
  scene "$OUT/many.yaml" "{play: true}" 256 1 "$d" "$steps"
  sed -i 's/range: \[0, 1\]/range: [0, 65535]/' "$OUT/many.yaml"
  farm "many_$steps" 2 "$OUT/many.yaml" 1
  read -r _ _ _ _ _ first <<<"$(summary "many_$steps" 2)"
  echo "first,2,32,$steps,1,,,,,,$first" >>"$OUT/time-series.csv"
  echo "| $steps | $first |"
done
