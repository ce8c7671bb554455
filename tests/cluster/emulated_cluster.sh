#!/usr/bin/env bash
# Runs the farm of compose.yaml on an emulated cluster: every process on its own host (a
# network namespace with one veth link to a switch namespace holding a bridge), links
# rate-limited with tc's tbf qdisc in both directions, the farm over TCP between the hosts'
# addresses with CURVE on (as across real machines). Needs root and iproute2.
#
#   tests/cluster/emulated_cluster.sh [--rate RATE] [--mtu BYTES] [--out DIR] [--bin DIR]
#                                     [--cut A,B,K] [--pin-renderers] [-- tessera-up args]
#     --rate   link rate per host, tc syntax (100mbit, 1gbit) or "unlimited" (default)
#     --out    folder for frames, metrics.jsonl, farm.log and links.tsv (default out/cluster)
#     --bin    folder of the tessera binaries (default build/bin)
#     --mtu    bytes per packet on every link (default 1500, Ethernet's; 9000: jumbo frames,
#              about the same bytes in fewer packets, 10-17x fewer as counted here, each of
#              which costs the emulation's queues, timers and bridge CPU on this machine's cores)
#     --cut A,B,K  once K frames are done, host A loses its route to host B (a blackhole
#              route: what A sends to B vanishes, as behind a failed link, and so B's TCP to A
#              stalls too, its acknowledgements lost; both still reach the other hosts)
#     --pin-renderers  renderer i runs on the i-th core this script may use (round robin),
#              with one ray-casting thread unless TESSERA_THREADS says otherwise, as on hosts
#              of their own; the other stages float. With as many renderers as cores, a
#              renderer's idle time is idle, not lent to another renderer.
# The farm's settings come from the environment as for tessera-up (TESSERA_RENDERERS,
# TESSERA_COMPOSITORS, TESSERA_FRAMES, TESSERA_CODEC, TESSERA_SCENE...). links.tsv has one
# line per host: host, bytes it sent, bytes it received, packets it sent, packets it received
# (counted on the switch side).
# Every namespace is removed at exit, also on failure or Ctrl-C; namespaces left by a run
# that was killed with SIGKILL are removed by the next run.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
rate=unlimited out=out/cluster bin="$root/build/bin" cut= mtu=1500 pin=
while [ $# -gt 0 ]; do
  case "$1" in
    --rate) rate=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --bin) bin=$2; shift 2 ;;
    --cut) cut=$2; shift 2 ;;
    --mtu) mtu=$2; shift 2 ;;
    --pin-renderers) pin=1; shift ;;
    --) shift; break ;;
    *) echo "emulated_cluster.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
[[ "$mtu" =~ ^[0-9]+$ ]] && [ "$mtu" -ge 1280 ] && [ "$mtu" -le 9000 ] ||
  { echo "emulated_cluster.sh: --mtu $mtu: expected bytes from 1280 to 9000" >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "emulated_cluster.sh: needs root (network namespaces)" >&2; exit 2; }
command -v ip >/dev/null && command -v tc >/dev/null || { echo "emulated_cluster.sh: needs iproute2 (ip, tc)" >&2; exit 2; }
mkdir -p "$out"; out=$(cd "$out" && pwd); bin=$(cd "$bin" && pwd)

tag="tcl$$"                       # namespaces and links of this run
state=$(mktemp -d "/tmp/tessera-cluster.XXXXXX")
cutter=
cleanup() {
  [ -n "$cutter" ] && kill "$cutter" 2>/dev/null || true
  for ns in $(ip netns list | awk '{print $1}' | grep "^$tag-" || true); do ip netns pids "$ns" 2>/dev/null | xargs -r kill -9 2>/dev/null || true; ip netns del "$ns" 2>/dev/null || true; done
  rm -rf "$state"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
# Namespaces of earlier runs whose script is gone (killed with SIGKILL).
for ns in $(ip netns list | awk '{print $1}' | grep -E '^tcl[0-9]+-' || true); do
  pid=${ns#tcl}; pid=${pid%%-*}
  kill -0 "$pid" 2>/dev/null || { ip netns pids "$ns" 2>/dev/null | xargs -r kill -9 2>/dev/null || true; ip netns del "$ns" 2>/dev/null || true; }
done

renderers=${TESSERA_RENDERERS:-2} compositors=${TESSERA_COMPOSITORS:-1}
hosts=(master display)
for ((i = 1; i <= renderers; i++)); do hosts+=("renderer-$i"); done
for ((i = 1; i <= compositors; i++)); do hosts+=("compositor-$i"); done

if [ -n "$cut" ]; then
  IFS=, read -r cut_from cut_to cut_after <<< "$cut"
  [[ " ${hosts[*]} " == *" $cut_from "* && " ${hosts[*]} " == *" $cut_to "* && "$cut_from" != "$cut_to" &&
     "$cut_after" =~ ^[0-9]+$ ]] ||
    { echo "emulated_cluster.sh: --cut $cut: expected HOST,HOST,FRAMES with two of: ${hosts[*]}" >&2; exit 2; }
fi

. "$root/tests/cluster/tbf.sh"
sw="$tag-sw"
ip netns add "$sw"
ip -n "$sw" link add br0 type bridge
ip -n "$sw" link set br0 up
mkdir -p "$state/hosts"
n=0
for h in "${hosts[@]}"; do
  n=$((n + 1)); ns="$tag-$h"; addr="10.77.0.$n"
  ip netns add "$ns"
  ip link add "${tag}h$n" type veth peer name "${tag}s$n"
  ip link set "${tag}h$n" netns "$ns" name eth0
  ip link set "${tag}s$n" netns "$sw"
  ip -n "$sw" link set "${tag}s$n" mtu "$mtu" master br0 up
  ip -n "$ns" addr add "$addr/24" dev eth0
  ip -n "$ns" link set eth0 mtu "$mtu" up
  ip -n "$ns" link set lo up
  tbf_limit "$rate" "$ns" eth0          # what the host sends
  tbf_limit "$rate" "$sw" "${tag}s$n"   # what the host receives
  echo "$addr" > "$state/hosts/$h.ip"
  echo "$ns" > "$state/hosts/$h.ns"
  echo "${tag}s$n" > "$state/hosts/$h.link"
done

"$bin/tessera-keys" "$state/keys" >/dev/null
export TESSERA_ENDPOINTS="tcp://$(cat "$state/hosts/master.ip"):5550"
export TESSERA_DISPLAY_HOST=$(cat "$state/hosts/display.ip")
export TESSERA_KEYS="$state/keys" TESSERA_CURVE=on TESSERA_WINDOW=off TESSERA_OUT="$out"
export EMULATED_CLUSTER_STATE="$state"
if [ -n "$pin" ]; then
  command -v taskset >/dev/null || { echo "emulated_cluster.sh: --pin-renderers needs taskset (util-linux)" >&2; exit 2; }
  cpus=()  # the cores this process may run on, e.g. "0-1" or "2,5-6"
  IFS=, read -ra ranges <<<"$(awk '/^Cpus_allowed_list/ {print $2}' /proc/self/status)"
  for r in "${ranges[@]}"; do for ((c = ${r%-*}; c <= ${r#*-}; c++)); do cpus+=("$c"); done; done
  echo "${cpus[*]}" > "$state/pin-renderers"
  export TESSERA_THREADS=${TESSERA_THREADS:-1}
fi
echo "emulated cluster: ${#hosts[@]} hosts, links $rate (MTU $mtu), endpoints $TESSERA_ENDPOINTS, output $out"
if [ -n "$cut" ]; then
  rm -f "$out/metrics.jsonl"
  (  # polls the master's metrics (one line per frame done) for at most 10 minutes
    for ((i = 0; i < 6000; i++)); do
      if [ "$(cat "$out/metrics.jsonl" 2>/dev/null | wc -l)" -ge "$cut_after" ]; then
        ip -n "$(cat "$state/hosts/$cut_from.ns")" route add blackhole "$(cat "$state/hosts/$cut_to.ip")/32"
        echo "emulated cluster: after $cut_after frames, $cut_from's link to $cut_to is cut"
        exit 0
      fi
      sleep 0.1
    done
  ) &
  cutter=$!
fi
set +e
"$bin/tessera-up" "$root/compose.yaml" --launch-with "$root/tests/cluster/on_host.sh" "$@" 2>&1 | tee "$out/farm.log"
status=${PIPESTATUS[0]}
set -e
: > "$out/links.tsv"; : > "$out/qdisc.txt"
for h in "${hosts[@]}"; do
  link=$(cat "$state/hosts/$h.link")
  # The switch side sends what the host receives and receives what the host sends.
  st="/sys/class/net/$link/statistics"
  read -r tx rx txp rxp <<< "$(ip netns exec "$sw" cat "$st/rx_bytes" "$st/tx_bytes" "$st/rx_packets" "$st/tx_packets" | tr '\n' ' ')"
  printf '%s\t%s\t%s\t%s\t%s\n' "$h" "$tx" "$rx" "$txp" "$rxp" >> "$out/links.tsv"
  { echo "== $h"; ip netns exec "$tag-$h" tc -s qdisc show dev eth0; ip netns exec "$sw" tc -s qdisc show dev "$link"
    ip netns exec "$tag-$h" nstat -az TcpRetransSegs TcpExtTCPTimeouts TcpExtTCPLossProbes 2>/dev/null | tail -n +2; } >> "$out/qdisc.txt"
done
exit "$status"
