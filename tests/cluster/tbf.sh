# Sourced by the emulated-cluster scripts: tbf_limit RATE NS DEV rate-limits what DEV sends
# (DEV in network namespace NS; NS "-" is this one) to RATE in tc syntax (100mbit, 2mbit;
# "unlimited" does nothing). tbf needs a bucket of at least one timer tick of traffic; 64 KiB
# keeps short bursts whole.
tbf_limit() {
  local rate=$1 ns=$2 dev=$3
  [ "$rate" = unlimited ] && return 0
  local bits; bits=$(numfmt --from=si "$(echo "${rate%bit}" | tr a-z A-Z)")
  local burst=$((bits / 8 / 250)); [ "$burst" -ge 65536 ] || burst=65536
  if [ "$ns" = - ]; then tc qdisc add dev "$dev" root tbf rate "$rate" burst "$burst" latency 50ms
  else ip netns exec "$ns" tc qdisc add dev "$dev" root tbf rate "$rate" burst "$burst" latency 50ms; fi
}
