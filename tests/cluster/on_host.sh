#!/usr/bin/env bash
# tessera-up --launch-with wrapper of the emulated cluster: runs one stage on its own host
# (network namespace), bound to and advertising that host's address, as on a real machine.
set -euo pipefail
state=${EMULATED_CLUSTER_STATE:?set by emulated_cluster.sh}
host=$TESSERA_SERVICE
case "$host" in renderer | compositor) host="$host-$TESSERA_REPLICA" ;; esac
[ -f "$state/hosts/$host.ns" ] || { echo "on_host.sh: no emulated host for $host" >&2; exit 2; }
export TESSERA_BIND_HOST=$(cat "$state/hosts/$host.ip")
export TESSERA_ADVERTISE_HOST=ip  # what Swarm tasks use: the address on the route to the master
pin=()  # --pin-renderers: renderer i on the i-th allowed core, round robin
if [ -f "$state/pin-renderers" ] && [ "$TESSERA_SERVICE" = renderer ]; then
  read -ra cpus < "$state/pin-renderers"
  pin=(taskset -c "${cpus[$(( (TESSERA_REPLICA - 1) % ${#cpus[@]} ))]}")
fi
exec ip netns exec "$(cat "$state/hosts/$host.ns")" ${pin[@]+"${pin[@]}"} "$@"
