#!/usr/bin/env bash
# Four "hosts" on one private LAN, without containers: network namespaces this script creates
# (three workers, one aggregator) whose veth links meet on a Linux bridge that lives in a fifth
# namespace of its own. Nothing is created in the caller's namespace, and everything is deleted
# on exit, failure or not. LCM runs with ttl=1, as on a real LAN: multicast crosses the bridge
# (one L2 segment, no router hop) and has nowhere else to go. Run by CTest:
#   multihost.sh DICESIM_BINARY LCM_INJECT_BINARY SCENARIO
# Scenarios:
#   lan       3 workers on 3 hosts + the aggregator on a 4th == `dicesim toss` (JSON compared as in
#             lcm_scenarios.sh); every worker tossed, so the batches really crossed the bridge
#   link_cut  the same, but one worker host's link is cut mid-run (`ip link set ... down` on its
#             bridge port): the aggregator re-leases the lost work, the counts stay identical
set -euo pipefail

skip() {  # skip REASON: a CTest skip, except under CI (a test that cannot run there fails)
  if [ -n "${CI:-}" ]; then echo "FAIL: cannot run under CI=$CI: $1" >&2; exit 1; fi
  echo "SKIP: $1"; exit 77
}
if [ "$(id -u)" -ne 0 ]; then skip "network namespaces need root"; fi
command -v ip > /dev/null || skip "iproute2 (ip) not installed"

bin=$1 inject=$2 scenario=$3
src_dir=$(cd "$(dirname "$0")/../.." && pwd)
cd "$src_dir"
scene=scenes/paper/die1.toml
seed=17

# Names unique to this run, so parallel CTest jobs (and leftovers of a killed run) never collide.
tag="dsmh$$$(printf '%04x' $((RANDOM % 65536)))"
ns_br="$tag-br" ns_agg="$tag-agg"
ns_w=("$tag-w1" "$tag-w2" "$tag-w3")
work=$(mktemp -d /tmp/dicesim-mh-XXXXXX)
pids=()
made_ns=()
cleanup() {
  set +e
  for p in "${pids[@]}"; do kill -9 "$p" 2> /dev/null; done
  wait 2> /dev/null
  # Any process still inside a namespace (none expected) would keep it alive: kill those too.
  for ns in "${made_ns[@]}"; do
    for p in $(ip netns pids "$ns" 2> /dev/null); do kill -9 "$p" 2> /dev/null; done
  done
  # Deleting the bridge namespace deletes the bridge and every veth pair with it.
  for ns in "${made_ns[@]}"; do ip netns del "$ns" 2> /dev/null; done
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

fail() {
  echo "FAIL [multihost $scenario]: $*" >&2
  for f in "$work"/*.err; do [ -e "$f" ] && { echo "--- $f" >&2; tail -n 20 "$f" >&2; }; done
  exit 1
}

# --- the network: 10.231.7.0/24, hosts .1-.3 workers, .10 the aggregator ------------------
addns() { ip netns add "$1"; made_ns+=("$1"); ip -n "$1" link set lo up; }
addns "$ns_br"
ip -n "$ns_br" link add br0 type bridge mcast_snooping 0  # flood multicast: no IGMP querier here
ip -n "$ns_br" link set br0 up
# host NS ADDR PORT: a namespace whose eth0 is a veth into the bridge (its bridge end is PORT).
host() {
  local ns=$1 addr=$2 port=$3
  addns "$ns"
  ip -n "$ns_br" link add "$port" type veth peer name eth0 netns "$ns"
  ip -n "$ns_br" link set "$port" master br0 up
  ip -n "$ns" addr add "$addr/24" dev eth0
  ip -n "$ns" link set eth0 multicast on up
  # No default route on this LAN: multicast needs its own route out of eth0 (README, Scaling out).
  ip -n "$ns" route add 224.0.0.0/4 dev eth0
}
for k in 1 2 3; do host "${ns_w[$((k - 1))]}" "10.231.7.$k" "p$k"; done
host "$ns_agg" 10.231.7.10 pagg

# One port per run (as `dicesim run` does) and ttl=1: the LAN setting of README, Scaling out.
export LCM_DEFAULT_URL="udpm://239.255.76.67:$((30000 + $$ % 20000))?ttl=1"
in_ns() { local ns=$1; shift; ip netns exec "$ns" "$@"; }

stable() { sed -E 's/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//g; s/"tosses_per_s":[^,}]*,?//; s/"seconds":[^,}]*,?//g' "$1"; }  # "seconds": auto's pilot time
health() { grep -oE "$1 [0-9]+" "$2" | tail -n1 | grep -oE '[0-9]+$' || echo 0; }
reference() { "$bin" toss "$scene" --tosses "$n" --seed "$seed" --threads "$1" --json > "$work/ref.json"; }
same_as_reference() {
  [ -s "$work/out.json" ] || fail "no JSON from the distributed run"
  if [ "$(stable "$work/ref.json")" != "$(stable "$work/out.json")" ]; then
    echo "reference:   $(stable "$work/ref.json")" >&2
    echo "distributed: $(stable "$work/out.json")" >&2
    fail "counts differ from dicesim toss"
  fi
}
workers() {
  for k in 1 2 3; do
    in_ns "${ns_w[$((k - 1))]}" "$bin" worker --once 2> "$work/worker$k.err" &
    pids+=($!)
  done
}
# A worker logs its run's end when it hears the aggregator's final message, which can come a
# moment after the aggregator has exited: waits up to 10 s for the line.
tossed() { for ((t = 0; t < 100; t++)); do grep -qE "ended: finished \([1-9][0-9]* tosses" "$work/worker$1.err" && return 0; sleep 0.1; done; return 1; }

case "$scenario" in
  lan)
    n=150000
    reference 1
    workers
    in_ns "$ns_agg" "$bin" aggregate "$scene" --tosses "$n" --seed "$seed" --json --timeout 50 \
      > "$work/out.json" 2> "$work/agg.err" || fail "aggregate exited $?"
    same_as_reference
    for k in 1 2 3; do tossed $k || fail "worker on host $k did no tosses (did multicast cross the bridge?)"; done
    ;;
  link_cut)
    n=1000000
    reference 2
    workers
    in_ns "$ns_agg" "$bin" aggregate "$scene" --tosses "$n" --seed "$seed" --json --timeout 50 \
      > "$work/out.json" 2> "$work/agg.err" &
    agg=$!
    pids+=("$agg")
    # Mid-run by construction: the cut comes when the aggregator's own broadcast says 10% are in.
    in_ns "$ns_agg" "$inject" progress 0.1 40 || fail "the run never reached 10%, or finished before the cut"
    ip -n "$ns_br" link set p1 down
    echo "cut host 1's link (bridge port p1 down) at 10%"
    wait "$agg" || fail "aggregate exited $?"
    same_as_reference
    released=$(health re-leased "$work/agg.err")
    [ "$released" -gt 0 ] || fail "nothing was re-leased after the cut (was host 1 working?)"
    tossed 2 && tossed 3 || fail "a worker on a connected host did no tosses"
    echo "re-leased after the cut: $released tosses"
    ;;
  *) echo "unknown scenario $scenario" >&2; exit 2 ;;
esac
grep -h "batches" "$work/agg.err"
echo "PASS [multihost $scenario]"
