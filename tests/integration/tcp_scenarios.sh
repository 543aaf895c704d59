#!/usr/bin/env bash
# Distributed runs over LCM's TCP hub (lcm.lcm.TCPService from liblcm-java, `dicesim hub`) where
# multicast cannot work: a private network namespace with only loopback, multicast off on it and
# every packet to 224.0.0.0/4 dropped by nftables. Run by CTest, one scenario per test:
#   tcp_scenarios.sh DICESIM_BINARY LCM_INJECT_BINARY SCENARIO
# Scenarios:
#   three_workers  three workers and an aggregator through the hub: toss's counts
#   kill9          a worker killed (SIGKILL) mid-run: the same counts
#   hub_restart    the hub killed mid-run and restarted on its port: LCM's tcpq clients reconnect,
#                  the run finishes with the same counts, and a `dicesim watch` (which only
#                  listens) reconnects too and sees it finish
#   key            an authenticated run (--key-file) over TCP: the same counts, and a worker with
#                  another key's messages are all dropped (it tosses nothing that counts)
#   run_tcp        dicesim run --transport tcp --workers 2 (a hub of its own): the same counts
#   no_multicast   proof of the setup: a UDP multicast run cannot even start here
# Under CI=true a scenario that cannot run (no root, no namespace, no java) fails.
set -euo pipefail
net_multicast=off  # private_net.sh: lo without multicast, no 224/4 route
. "$(dirname "$0")/private_net.sh" tcp "$@"
bin=$1 inject=$2 scenario=$3
command -v java > /dev/null || skip "no java (Debian package default-jre-headless)"
[ -f "${DICESIM_LCM_JAR:-/usr/share/java/lcm.jar}" ] || skip "no LCM jar (Debian package liblcm-java)"
command -v nft > /dev/null || skip "no nft (Debian package nftables)"

nft add table inet dicesim_nomc
nft add chain inet dicesim_nomc out '{ type filter hook output priority 0; policy accept; }'
nft add rule inet dicesim_nomc out ip daddr 224.0.0.0/4 counter drop

port=7700
export LCM_DEFAULT_URL="tcpq://127.0.0.1:$port"
scene=scenes/paper/die1.toml
seed=11
n=20000
echo "scenario $scenario over $LCM_DEFAULT_URL"

fail() { echo "FAIL [$scenario]: $*" >&2; for f in "$work"/*.err; do echo "--- $f" >&2; tail -n 20 "$f" >&2; done; exit 1; }
stable() { sed -E 's/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//g; s/"tosses_per_s":[^,}]*,?//; s/"seconds":[^,}]*,?//g' "$1"; }  # threads: also provenance's; seconds: auto's pilot time
reference() { "$bin" toss "$scene" --tosses "$n" --seed "$seed" --threads 2 --json > "$work/ref.json"; }
same_as_reference() {
  [ -s "$1" ] || fail "no JSON from the distributed run"
  if [ "$(stable "$work/ref.json")" != "$(stable "$1")" ]; then
    echo "reference:   $(stable "$work/ref.json")" >&2
    echo "distributed: $(stable "$1")" >&2
    fail "counts differ from dicesim toss"
  fi
}
health() { grep -oE "$1 [0-9]+" "$2" | tail -n1 | grep -oE '[0-9]+$' || echo 0; }
# The hub: dicesim hub on $port; waits until it accepts connections.
hub() {
  "$bin" hub --port "$port" > "$work/hub.out" 2> "$work/hub.err" & hubpid=$!; pids+=($hubpid)
  for ((t = 0; t < 300; t++)); do (exec 3<> "/dev/tcp/127.0.0.1/$port") 2> /dev/null && return 0; sleep 0.1; done
  fail "the hub did not accept connections within 30 s"
}
nworkers=0
declare -a wpid
worker() { nworkers=$((nworkers + 1)); "$bin" worker --once "$@" 2> "$work/worker$nworkers.err" & wpid[$nworkers]=$!; pids+=($!); }
listening() { for ((t = 0; t < 200; t++)); do [ "$(cat "$work"/worker*.err 2>/dev/null | grep -c "listening on")" -ge "$1" ] && return 0; sleep 0.1; done; fail "workers not listening after 20 s"; }
aggregate() { "$bin" aggregate "$scene" --tosses "$n" --seed "$seed" --json --timeout 150 "$@" > "$work/out.json" 2> "$work/agg.err"; }
# "ended: finished (N tosses" -- or, when the hub had not relayed the aggregator's closing messages
# before it exited, "ended: no run_start heard for a while (N tosses" 5 s later: either way N > 0.
did_toss() { grep -qE "ended: .*\([1-9][0-9]* tosses" "$1"; }

case "$scenario" in
  three_workers)
    n=150000
    reference
    hub
    worker; worker; worker
    listening 3
    aggregate || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    for i in 1 2 3; do
      for ((t = 0; t < 100; t++)); do did_toss "$work/worker$i.err" && break; sleep 0.1; done
      did_toss "$work/worker$i.err" || fail "worker $i did no tosses"
    done
    ;;
  kill9)
    n=1000000
    reference
    hub
    worker; worker; worker
    listening 3
    aggregate & agg=$!
    "$inject" progress 0.1 120 || fail "the run never reached 10%, or finished before the kill"
    kill -9 "${wpid[1]}"
    wait "$agg" || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    [ "$(health re-leased "$work/agg.err")" -gt 0 ] || fail "nothing was re-leased after kill -9 (was the victim working?)"
    ;;
  hub_restart)
    n=1000000
    reference
    hub
    worker; worker
    listening 2
    # A process that only listens (watch) follows the run across the restart too: it reconnects by
    # itself (wire::listen_timeout), prints the finished answer and its provenance.
    "$bin" watch --until-finished --timeout 150 > "$work/watch.out" 2> "$work/watch.err" & watchp=$!; pids+=($watchp)
    aggregate & agg=$!
    "$inject" progress 0.1 120 || fail "the run never reached 10%, or finished before the hub was killed"
    kill -9 "$hubpid"; wait "$hubpid" 2> /dev/null || true
    sleep 2
    hub
    wait "$agg" || fail "aggregate exited $? after the hub's restart"
    same_as_reference "$work/out.json"
    wait "$watchp" || fail "dicesim watch exited $? across the hub's restart (it did not reconnect)"
    grep -q "FINISHED $n/$n" "$work/watch.out" || fail "dicesim watch did not see the run finish after the hub's restart"
    grep -q "provenance: " "$work/watch.out" || fail "dicesim watch printed no provenance for the finished run"
    ;;
  key)
    n=150000
    reference
    key=$work/run.key other=$work/other.key
    (umask 077; od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$key"; od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$other")
    hub
    worker --key-file "$key"; worker --key-file "$key"; worker --key-file "$other"
    listening 3
    aggregate --key-file "$key" || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    dropped=$(health unauthenticated "$work/agg.err")
    echo "unauthenticated messages dropped by the aggregator: $dropped"
    [ "$dropped" -gt 0 ] || fail "the aggregator dropped nothing from the worker with another key"
    ;;
  run_tcp)
    n=100000
    reference
    "$bin" run "$scene" --tosses "$n" --seed "$seed" --workers 2 --transport tcp --json > "$work/out.json" 2> "$work/run.err" ||
      fail "run --transport tcp exited $?"
    same_as_reference "$work/out.json"
    # The hub it started is gone with it: nothing listens in this namespace any more.
    [ -z "$(ss -Hltn)" ] || fail "the run's hub outlived the run: $(ss -Hltnp)"
    ;;
  no_multicast)
    # The same run over UDP multicast cannot work here: the setup really has no multicast.
    n=2000
    worker --lcm "udpm://239.255.76.67:7667?ttl=0"
    code=0
    "$bin" aggregate "$scene" --tosses "$n" --seed "$seed" --json --timeout 5 --lcm "udpm://239.255.76.67:7667?ttl=0" \
      > "$work/out.json" 2> "$work/agg.err" || code=$?
    [ "$code" -ne 0 ] || fail "a UDP multicast run finished in a namespace without multicast"
    ;;
  *) echo "unknown scenario $scenario" >&2; exit 2 ;;
esac
echo "PASS [$scenario]"
