#!/usr/bin/env bash
# Peak memory of every farm process against the volume: the farm renders one frame of a
# SIZE^3 uint16 raw volume (SIZE^3 x 2 bytes on disk, written once by tessera-dump-volume a
# slab at a time) with 1, 2 and 4 renderers; each process logs its peak resident memory
# at exit. Writes OUT/memory.csv and prints a Markdown table.
# Usage: tests/bench/memory_bench.sh [SIZE=512] [OUT=bench-out/memory] [BUILD=build]
set -euo pipefail
SIZE=${1:-512}
OUT=$(realpath -m "${2:-bench-out/memory}")
BUILD=$(realpath "${3:-build}")
HERE=$(cd "$(dirname "$0")/../.." && pwd)
mkdir -p "$OUT"
RAW="$OUT/shell_${SIZE}.raw"
if [ ! -s "$RAW" ]; then "$BUILD/bin/tessera-dump-volume" --type uint16 hollow-shell "$SIZE" 1 "$RAW" >/dev/null; fi
cat >"$OUT/scene.yaml" <<EOF
volume: {file: $RAW, dims: [$SIZE, $SIZE, $SIZE], type: uint16}
transfer_function: cool-to-warm
image: [256, 256]
EOF
file_mib=$(( SIZE * SIZE * SIZE * 2 / 1048576 ))
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')
echo "renderers,volume_voxels,file_mib,master_mib,renderer_max_mib,renderer_min_mib,renderer_read_max_mib,wall_s" >"$OUT/memory.csv"
echo "| renderers | volume | file | master peak | largest renderer peak | smallest renderer peak | most a renderer read | wall time |"
echo "|---|---|---|---|---|---|---|---|"
for n in 1 2 4; do
  log="$OUT/farm_$n.log"
  start=$(date +%s%N)
  TESSERA_RUN="mem$$n$n" TESSERA_SCENE="$OUT/scene.yaml" TESSERA_RENDERERS=$n TESSERA_COMPOSITORS=1 \
    TESSERA_FRAMES=1 TESSERA_OUT="$OUT/out_$n" TESSERA_WINDOW=off TESSERA_ENDPOINTS="ipc://$OUT/sockets_$n" \
    timeout 900 "$BUILD/bin/tessera-up" "$HERE/compose.yaml" >"$log" 2>&1 || { tail -20 "$log"; exit 1; }
  wall=$(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.1f", (b - a) / 1e9 }')
  peaks() { grep -E "^$1-?[0-9]* +\|.*peak memory" "$log" | sed -E 's/.*peak memory ([0-9.]+) MiB.*/\1/'; }
  master=$(peaks master | head -1)
  rmax=$(peaks renderer | sort -g | tail -1 || true)
  rmin=$(peaks renderer | sort -g | head -1)
  # What a renderer read of the file (its bricks and ghost voxels; "read N MiB of volume samples").
  rread=$(grep -E "^renderer-?[0-9]* +\|.*MiB of volume samples" "$log" | sed -E 's/.*read ([0-9.]+) MiB.*/\1/' | sort -g | tail -1 || true)
  [ "$(peaks renderer | wc -l)" -eq "$n" ] || { echo "expected $n renderer peaks in $log" >&2; exit 1; }
  echo "$n,$SIZE^3,$file_mib,$master,$rmax,$rmin,${rread:-},$wall" >>"$OUT/memory.csv"
  printf '| %d | %d^3 uint16 | %d MiB | %.0f MiB | %.0f MiB | %.0f MiB | %s MiB | %.1f s |\n' "$n" "$SIZE" "$file_mib" "$master" "$rmax" "$rmin" "${rread:--}" "$wall"
done
echo
echo "CPU: $cpu; csv: $OUT/memory.csv"
