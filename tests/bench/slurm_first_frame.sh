#!/usr/bin/env bash
# Time to the first frame under Slurm: on the one-host test cluster (root; two slurmd
# nodes), submits the README's batch script (docs/tessera.sbatch) with the built-in default
# scene (1024x1024, 2 renderers + 1 compositor) RUNS times, and from each job's log takes the
# step's start (tessera-up --slurm's first line, before srun) and the display's frame 0.
# Also the time from sbatch to the job's end. Writes OUT/slurm-first-frame.csv.
# Usage: sudo tests/bench/slurm_first_frame.sh [RUNS=5] [OUT=bench-out/slurm] [BUILD=build]
set -euo pipefail
RUNS=${1:-5}
OUT=$(realpath -m "${2:-bench-out/slurm}")
BUILD=$(realpath "${3:-build}")
HERE=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$OUT" && mkdir -p "$OUT"
cat >"$OUT/runs.sh" <<SCRIPT
set -euo pipefail
source "$HERE/tests/slurm/jobs.sh"
export PATH="$BUILD/bin:\$PATH" TESSERA_FRAMES=3 TESSERA_WINDOW=off
ms() { date -d "\$(date +%F) \$1" +%s%3N; }
echo "run,step_start_to_first_frame_ms,submit_to_end_ms" >"$OUT/slurm-first-frame.csv"
for i in \$(seq $RUNS); do
  farm="$OUT/run\$i"; mkdir -p "\$farm"; cp "$HERE/compose.yaml" "\$farm/"
  t0=\$(date +%s%3N)
  job=\$(cd "\$farm" && sbatch --parsable --overcommit "$HERE/docs/tessera.sbatch")
  state=\$(wait_job \$job 120); t1=\$(date +%s%3N)
  [ "\$state" = "COMPLETED 0:0" ] || { echo "run \$i: \$state"; cat "\$farm"/tessera-*.log; exit 1; }
  log=\$(cat "\$farm"/tessera-\$job.log)
  start=\$(grep -m1 -o '^[0-9:.]* \[tessera-up\]' <<<"\$log" | cut -d' ' -f1)
  first=\$(grep -m1 '\[display\] info frame 0 ' <<<"\$log" | sed 's/.*| \([0-9:.]*\) .*/\1/')
  echo "\$i,\$(( \$(ms \$first) - \$(ms \$start) )),\$(( t1 - t0 ))" >>"$OUT/slurm-first-frame.csv"
done
SCRIPT
"$HERE/tests/slurm/one_host_slurm.sh" --nodes 2 -- bash "$OUT/runs.sh"
cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')
echo "CPU: $cpu, $(nproc) cores; default scene 1024x1024, 2 renderers + 1 compositor"
column -s, -t "$OUT/slurm-first-frame.csv"
