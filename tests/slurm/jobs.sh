# Helpers for tests that submit jobs to the one-host cluster (one_host_slurm.sh); source it.

# "STATE EXIT" of a job, e.g. "COMPLETED 0:0" (scontrol keeps ended jobs for MinJobAge; a
# heterogeneous job's first line is its leader's).
job_state() {
  local line
  line=$(scontrol show job -o "$1" 2>/dev/null | head -n 1) || true
  echo "$(sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' <<<"$line") $(sed -n 's/.* ExitCode=\([0-9:]*\).*/\1/p' <<<"$line")"
}

# Waits (at most $2 seconds) until job $1 has ended; prints its "STATE EXIT".
wait_job() {
  local end=$((SECONDS + $2)) s
  while [ $SECONDS -lt $end ]; do
    s=$(job_state "$1")
    case "$s" in PENDING*|RUNNING*|CONFIGURING*|COMPLETING*|" "*) sleep 0.1 ;; *) echo "$s"; return 0 ;; esac
  done
  echo "TIMEOUT $(job_state "$1")"
}

# Waits (at most $2 seconds) until file $1 exists.
wait_file() {
  local end=$((SECONDS + $2))
  while [ $SECONDS -lt $end ]; do [ -e "$1" ] && return 0; sleep 0.05; done
  echo "wait_file: no $1 after $2 s" >&2
  return 1
}

# PIDs of the processes working in folder $1 (a farm's tasks and stages run in the folder
# its job was submitted from).
farm_pids() {
  local p
  for p in /proc/[0-9]*; do
    [ "$(readlink "$p/cwd" 2>/dev/null)" = "$1" ] && echo -n "${p#/proc/} "
  done
  true
}

# Kills (SIGKILL) the first process (in /proc order) named $2 (its 15-character comm)
# working in folder $1.
kill_stage() {
  local p
  for p in $(farm_pids "$1"); do
    if [ "$(cat /proc/$p/comm 2>/dev/null)" = "$2" ]; then kill -KILL "$p" && echo "killed $2 $p"; return 0; fi
  done
  echo "kill_stage: no $2 in $1" >&2
  return 1
}

# Kills (SIGKILL) the task of service $2 in folder $1: the tessera-up --slurm-task process
# itself (its stage then gets SIGTERM from the kernel: PR_SET_PDEATHSIG).
kill_task() {
  local p
  for p in $(farm_pids "$1"); do
    if tr '\0' ' ' <"/proc/$p/cmdline" 2>/dev/null | grep -q -- "--slurm-task $2 "; then
      kill -KILL "$p" && echo "killed the $2 task $p"
      return 0
    fi
  done
  echo "kill_task: no $2 task in $1" >&2
  return 1
}
