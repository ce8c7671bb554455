#!/usr/bin/env bash
# Runs COMMAND with a viewer on its own emulated host: a network namespace joined to this one
# by a veth link rate-limited with tc's tbf in both directions. COMMAND finds the namespace in
# TESSERA_VIEWER_NETNS (run the browser with `ip netns exec`) and, in TESSERA_VIEWER_SERVER,
# this host's address on the link (where the display's web view must listen for that viewer).
# Needs root and iproute2. The namespace and link are removed at exit, also on failure or
# Ctrl-C; those of a run killed with SIGKILL are removed by the next run.
#   tests/web/viewer_link.sh RATE COMMAND...     (RATE: tc syntax, 2mbit, 100mbit, or unlimited)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
[ $# -ge 2 ] || { echo "usage: viewer_link.sh RATE COMMAND..." >&2; exit 2; }
rate=$1; shift
[ "$(id -u)" -eq 0 ] || { echo "viewer_link.sh: needs root (network namespaces)" >&2; exit 2; }
command -v ip >/dev/null && command -v tc >/dev/null || { echo "viewer_link.sh: needs iproute2 (ip, tc)" >&2; exit 2; }
. "$root/tests/cluster/tbf.sh"

remove() {  # remove TAG: its namespace (and processes) and its end of the link
  ip netns pids "$1-viewer" 2>/dev/null | xargs -r kill -9 2>/dev/null || true
  ip netns del "$1-viewer" 2>/dev/null || true
  ip link del "$1h" 2>/dev/null || true
}
for ns in $(ip netns list | awk '{print $1}' | grep -E '^tvl[0-9]+-viewer$' || true); do
  pid=${ns#tvl}; pid=${pid%-viewer}
  kill -0 "$pid" 2>/dev/null || remove "tvl$pid"
done
tag="tvl$$"
trap 'remove "$tag"' EXIT
trap 'exit 130' INT TERM
ns="$tag-viewer"
ip netns add "$ns"
ip link add "${tag}h" type veth peer name "${tag}v"
ip link set "${tag}v" netns "$ns"
ip addr add 10.78.0.1/30 dev "${tag}h"
ip link set "${tag}h" up
ip -n "$ns" addr add 10.78.0.2/30 dev "${tag}v"
ip -n "$ns" link set "${tag}v" up
ip -n "$ns" link set lo up
tbf_limit "$rate" - "${tag}h"            # to the viewer
tbf_limit "$rate" "$ns" "${tag}v"        # from the viewer
export TESSERA_VIEWER_NETNS="$ns" TESSERA_VIEWER_SERVER=10.78.0.1 TESSERA_VIEWER_RATE="$rate"
echo "viewer link: $rate, the viewer in namespace $ns, this host at $TESSERA_VIEWER_SERVER"
"$@"
