#!/bin/bash
# A one-host Slurm cluster for tests: munged, slurmctld and NODES slurmd (each its own
# node name and port, all on 127.0.0.1; partitions farm (all, default), compute and viz) from a slurm.conf written into a temporary folder;
# runs COMMAND with SLURM_CONF pointing at it and stops every daemon it started, also on
# failure or interruption. Needs root (SlurmUser=root) and Debian's slurmctld, slurmd,
# slurm-client and munge.
#   one_host_slurm.sh [--nodes N] [--dir DIR] -- COMMAND...
set -euo pipefail
nodes=1
dir=""
while [ $# -gt 0 ]; do
  case "$1" in
    --nodes) nodes="$2"; shift 2 ;;
    --dir) dir="$2"; shift 2 ;;
    --) shift; break ;;
    *) echo "one_host_slurm.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
[ $# -gt 0 ] || { echo "one_host_slurm.sh: no command" >&2; exit 2; }
# Exit 77 (the tests skip) only without root; as root a missing package is a failure.
[ "$(id -u)" = 0 ] || { echo "one_host_slurm.sh: needs root (SlurmUser=root)" >&2; exit 77; }
for b in munged slurmctld slurmd sbatch srun; do
  command -v "$b" >/dev/null || { echo "one_host_slurm.sh: $b is not installed (./setup.sh test installs it)" >&2; exit 1; }
done
own_dir=0
[ -n "$dir" ] || { dir=$(mktemp -d /tmp/tessera-slurm.XXXXXX); own_dir=1; }
mkdir -p "$dir"/{spool,state,log,munge}
chmod 700 "$dir/munge"

# A port nothing listens on, for slurmctld and each slurmd: random in 6000-9999, below both
# the farm's ports (10000-31999) and the kernel's ephemeral ports (where an outgoing
# connection could take it before the daemon binds), checked with ss, never one chosen before.
# Sets $port (no command substitution: its subshell would forget the ports chosen).
chosen=" "
free_port() {
  local p
  for _ in $(seq 100); do
    p=$((6000 + RANDOM % 4000))
    case "$chosen" in *" $p "*) continue ;; esac
    ss -Htan "sport = :$p" | grep -q . && continue
    chosen="$chosen$p "
    port=$p
    return
  done
  echo "one_host_slurm.sh: no free port" >&2
  exit 1
}
free_port
ctld_port=$port
cpus=$(nproc)

pids=()
cleanup() {
  # Jobs first (their slurmstepd outlive slurmd): cancel, then wait for them to go (10 s).
  if [ -n "${SLURM_CONF:-}" ] && [ ${#pids[@]} -gt 1 ]; then
    scancel --quiet --user=root 2>/dev/null || true
    for _ in $(seq 100); do
      [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
      sleep 0.1
    done
  fi
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  for _ in $(seq 50); do
    alive=0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=1; done
    [ $alive = 0 ] && break
    sleep 0.1
  done
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  # Anything a job of this cluster left (its environment names this slurm.conf).
  for p in $(grep -lsz "^SLURM_CONF=$dir/slurm.conf\$" /proc/[0-9]*/environ 2>/dev/null | cut -d/ -f3); do
    [ "$p" != $$ ] && kill -KILL "$p" 2>/dev/null || true
  done
  [ "$own_dir" = 1 ] && rm -rf "$dir"
  true
}
trap cleanup EXIT
trap 'exit 130' INT TERM

dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge/munge.key"
munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
  --pid-file="$dir/munge/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/seed"
for _ in $(seq 50); do [ -s "$dir/munge/munged.pid" ] && break; sleep 0.1; done
pids+=("$(cat "$dir/munge/munged.pid")")

{
  cat <<CONF
ClusterName=tessera-test
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
CommunicationParameters=NoInAddrAny
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool/%n
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd-%n.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd-%n.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SchedulerParameters=bf_interval=1
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
KillWait=5
InactiveLimit=0
MinJobAge=30
CONF
  for i in $(seq "$nodes"); do
    free_port
    echo "NodeName=node$i NodeHostname=localhost NodeAddr=127.0.0.1 Port=$port CPUs=$cpus State=UNKNOWN"
  done
  echo "PartitionName=farm Nodes=ALL Default=YES MaxTime=INFINITE State=UP OverSubscribe=FORCE:8"
  # For heterogeneous jobs (docs/tessera-hetjob.sbatch): the last node is the display's.
  if [ "$nodes" -ge 2 ]; then
    echo "PartitionName=compute Nodes=node[1-$((nodes - 1))] MaxTime=INFINITE State=UP OverSubscribe=FORCE:8"
    echo "PartitionName=viz Nodes=node$nodes MaxTime=INFINITE State=UP OverSubscribe=FORCE:8"
  fi
} > "$dir/slurm.conf"
export SLURM_CONF="$dir/slurm.conf"

slurmctld -D -i -f "$SLURM_CONF" > "$dir/log/slurmctld.out" 2>&1 &
pids+=($!)
for i in $(seq "$nodes"); do
  mkdir -p "$dir/spool/node$i"
  slurmd -D -N "node$i" -f "$SLURM_CONF" > "$dir/log/slurmd-node$i.out" 2>&1 &
  pids+=($!)
done
# Ready when every node is idle (bounded: 30 s).
for _ in $(seq 150); do
  idle=$(sinfo -h -N -p farm -o '%T' 2>/dev/null | grep -c '^idle' || true)
  [ "$idle" = "$nodes" ] && break
  sleep 0.2
done
if [ "$idle" != "$nodes" ]; then
  echo "one_host_slurm.sh: the cluster did not come up ($idle of $nodes nodes idle); logs in $dir/log" >&2
  tail -n 20 "$dir"/log/* >&2 || true
  exit 1
fi
"$@"
