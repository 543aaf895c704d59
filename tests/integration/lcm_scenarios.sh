#!/usr/bin/env bash
# Distributed-run scenarios with real processes, each inside a private network namespace that
# this script creates for itself (only loopback, with a multicast route): nothing it sends can
# leave the namespace. Run by CTest (tests/CMakeLists.txt), one scenario per test:
#   lcm_scenarios.sh DICESIM_BINARY LCM_INJECT_BINARY SCENARIO
# Scenarios: three_workers kill9 drop10 replay late_join hostile run_cmd sweep_workers interrupt target trace
#            forgery agg_restart
# Every scenario compares the distributed JSON with `dicesim toss --threads 1` after removing
# only the keys that may differ (elapsed_s, tosses_per_s, threads): identical counts, p, CIs.
set -euo pipefail

. "$(dirname "$0")/private_net.sh" it "$@"

bin=$1 inject=$2 scenario=$3

scene=scenes/paper/die1.toml
seed=11
n=20000
# A scenario name ending in _d20 or _d4 runs the same scenario on that die (scenes/dice/):
# everything that works for a d6 works for any number of outcomes.
case "$scenario" in
  *_d20) scene=scenes/dice/d20.toml; scenario=${scenario%_d20} ;;
  *_d4) scene=scenes/dice/d4.toml; scenario=${scenario%_d4} ;;
esac
# Those dice name no fidelity, so they would run `auto` (impulse, ~50x slower than paper): they are
# wire tests, kept on `paper`, the model they ran before auto became the default.
if [ "$scene" != scenes/paper/die1.toml ]; then
  printf 'extends = "%s"\n[sim]\nfidelity = "paper"\n' "$PWD/$scene" > "$work/die.toml"
  scene=$work/die.toml
fi
echo "scenario $scenario on $scene"

fail() { echo "FAIL [$scenario]: $*" >&2; for f in "$work"/*.err; do echo "--- $f" >&2; tail -n 20 "$f" >&2; done; exit 1; }
# The JSON without the keys that legitimately differ between runs.
stable() { sed -E 's/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//g; s/"tosses_per_s":[^,}]*,?//; s/"seconds":[^,}]*,?//g' "$1"; }  # "seconds": auto's pilot time
# Scenario (a) compares with one thread; the others use two (the counts are the same by
# construction, tested by (a) and by the unit tests) to keep the suite short.
reference() { "$bin" toss "$scene" --tosses "$n" --seed "$seed" --threads "${1:-2}" --json > "$work/ref.json"; }
same_as_reference() {
  [ -s "$1" ] || fail "no JSON from the distributed run"
  if [ "$(stable "$work/ref.json")" != "$(stable "$1")" ]; then
    echo "reference:   $(stable "$work/ref.json")" >&2
    echo "distributed: $(stable "$1")" >&2
    fail "counts differ from dicesim toss --threads 1"
  fi
}
# A number from the aggregator's closing health line, e.g. health duplicates agg.err
health() { grep -oE "$1 [0-9]+" "$2" | tail -n1 | grep -oE '[0-9]+$' || echo 0; }
# Starts worker number k (1, 2, ...): its log is worker<k>.err, its pid ${wpid[k]}.
nworkers=0
declare -a wpid
worker() { nworkers=$((nworkers + 1)); "$bin" worker --once "$@" 2> "$work/worker$nworkers.err" & wpid[$nworkers]=$!; pids+=($!); }
# Waits (up to 20 s) until workers 1..k have subscribed, so that a short run cannot end before one
# of them hears it: "did worker k toss?" is then a question about leasing, not process start-up.
listening() { for ((t = 0; t < 200; t++)); do [ "$(cat "$work"/worker*.err 2>/dev/null | grep -c "listening on")" -ge "$1" ] && return 0; sleep 0.1; done; fail "workers not listening after 20 s"; }
# A worker logs "ended: finished" when it hears the aggregator's final message, which can be a
# moment after the aggregator (or sweep) has exited: waits up to 10 s until FILE holds N such lines.
ended_finished() { for ((t = 0; t < 100; t++)); do [ "$(grep -cE "ended: finished${3:-}" "$1")" -ge "$2" ] && return 0; sleep 0.1; done; return 1; }
aggregate() { "$bin" aggregate "$scene" --tosses "$n" --seed "$seed" --json --timeout 150 "$@" > "$work/out.json" 2> "$work/agg.err"; }

case "$scenario" in
  three_workers)
    n=150000
    reference 1
    worker; worker; worker
    listening 3
    aggregate || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    for i in 1 2 3; do ended_finished "$work/worker$i.err" 1 " \\([1-9][0-9]* tosses" || fail "worker $i did no tosses"; done
    ;;
  kill9)
    n=1000000
    reference
    worker; worker; worker
    aggregate & agg=$!
    # Mid-run by construction: the kill comes when DICESIM_PROBABILITIES says 10% are in.
    "$inject" progress 0.1 60 || fail "the run never reached 10%, or finished before the kill"
    kill -9 "${wpid[1]}"
    wait "$agg" || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    [ "$(health re-leased "$work/agg.err")" -gt 0 ] || fail "nothing was re-leased after kill -9 (was the victim working?)"
    ;;
  drop10)
    nft add table inet dicesim_test
    nft add chain inet dicesim_test input '{ type filter hook input priority 0; policy accept; }'
    nft add rule inet dicesim_test input numgen random mod 10 0 counter drop
    n=200000
    reference
    worker; worker
    aggregate || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    dropped=$(nft list chain inet dicesim_test input | grep -oE 'packets [0-9]+' | grep -oE '[0-9]+')
    echo "packets dropped by nftables: $dropped; re-leased tosses: $(health re-leased "$work/agg.err")"
    [ "$dropped" -gt 0 ] || fail "nftables dropped nothing: the scenario tested nothing"
    ;;
  replay)
    # A worker restarted mid-run, and every batch published so far published again (recorded
    # with the stock lcm-logger, replayed with lcm-logplayer): nothing may count twice.
    n=1000000
    reference
    lcm-logger -q -f -c DICESIM_TOSS_BATCH "$work/batches.lcmlog" & logger=$!; pids+=($logger)
    worker; worker
    aggregate & agg=$!
    "$inject" progress 0.2 60 || fail "the run never reached 20%, or finished first"
    kill -9 "${wpid[1]}"
    worker
    kill -INT "$logger"; wait "$logger" || true
    lcm-logplayer -s 20 "$work/batches.lcmlog"
    wait "$agg" || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    [ "$(health duplicates "$work/agg.err")" -gt 0 ] || fail "no duplicates seen: the replay tested nothing"
    ended_finished "$work/worker3.err" 1 " \\([1-9][0-9]* tosses" || fail "the restarted worker did no tosses"
    ;;
  late_join)
    n=600000
    reference
    worker
    aggregate & agg=$!
    "$inject" progress 0.1 60 || fail "the run never reached 10%, or finished before the late worker"
    worker
    wait "$agg" || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    wait "${wpid[2]}" || fail "late worker exited $?"
    grep -qE "ended: finished \([1-9][0-9]* tosses" "$work/worker2.err" || fail "the late worker did no tosses"
    ;;
  hostile)
    # Order by construction, not by timing: the workers listen, then are stopped (SIGSTOP: the
    # kernel keeps what arrives for them). The aggregator announces and waits for workers; the
    # injector hears the run_start and sends every hostile message, all of which reach the
    # aggregator while no worker can end the run (a 0.4 s run once ended before the injector had
    # subscribed). Resumed, the workers read their queue in order: the real run_start first, then
    # the foreign one (ignored: busy with a live run) and the garbage, and serve the run.
    n=200000
    reference
    worker; worker
    listening 2
    kill -STOP "${wpid[1]}" "${wpid[2]}"
    aggregate & agg=$!
    "$inject" hostile > "$work/inject.out" || fail "inject failed"
    kill -CONT "${wpid[1]}" "${wpid[2]}"
    wait "$agg" || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    for k in 1 2; do wait "${wpid[$k]}" || fail "worker $k exited with $? after hostile messages"; done
    cat "$work/inject.out"; grep -E "batches" "$work/agg.err"
    # Every one of them reached the aggregator while it ran (loopback, paced sends): each is counted.
    for kind in foreign "out of range" malformed; do
      sent=$(grep -oE "$kind [0-9]+" "$work/inject.out" | grep -oE '[0-9]+$')
      [ "$(health "$kind" "$work/agg.err")" = "$sent" ] || fail "$kind: $sent sent, $(health "$kind" "$work/agg.err") counted"
    done
    ;;
  run3)
    # `dicesim run --workers 3` (its own worker processes) gives exactly `toss`'s counts.
    reference
    "$bin" run "$scene" --workers 3 --tosses "$n" --seed "$seed" --json > "$work/out.json" 2> "$work/run.err" ||
      fail "dicesim run exited $?"
    same_as_reference "$work/out.json"
    grep -q '"threads":3' "$work/out.json" || fail "threads should report the 3 workers"
    ;;
  run_cmd)
    reference
    url="udpm://239.255.76.67:$((30000 + $$ % 20000))?ttl=0"
    "$bin" run "$scene" --workers 2 --tosses "$n" --seed "$seed" --json --lcm "$url" --log-level debug > "$work/out.json" \
      2> "$work/run.err" || fail "dicesim run exited $?"
    same_as_reference "$work/out.json"
    grep -q '"threads":2' "$work/out.json" || fail "threads should report the 2 workers"
    # Its workers are forks that start with the run's compiled model, not exec'd processes.
    [ "$(grep -c "forked by .dicesim run. (no exec)" "$work/run.err")" = 2 ] || fail "run's workers were not forked without exec"
    sleep 0.2
    if pgrep -f -- "--lcm $url" > /dev/null; then fail "worker processes left behind"; fi
    ;;
  sweep_workers)
    # `dicesim sweep --workers`: every point a distributed run; the counts equal the in-process
    # sweep's at every point. First the outside worker alone (--workers 0 --lcm): it must serve
    # both points. Then one local worker process beside it: whether the outside one gets a lease
    # there is timing (a 6000-toss `paper` point takes ~15 ms, less than its compile under load:
    # CI once saw it miss the second point), so only the counts and the local worker are checked.
    sweep_args=(--param floor.restitution --values 0.3,0.9 --tosses 6000 --seed "$seed" --json)
    "$bin" sweep "$scene" "${sweep_args[@]}" --threads 2 > "$work/ref.json" || fail "in-process sweep exited $?"
    url="udpm://239.255.76.67:$((30000 + $$ % 20000))?ttl=0"
    "$bin" worker --lcm "$url" 2> "$work/worker1.err" & pids+=($!)  # serves every run, not --once
    strip() { jq -c 'del(.elapsed_s, .tosses_per_s, .threads, .workers, .provenance.threads)' "$1"; }
    "$bin" sweep "$scene" "${sweep_args[@]}" --workers 0 --lcm "$url" > "$work/out0.json" 2> "$work/sweep0.err" ||
      fail "dicesim sweep --workers 0 --lcm exited $?"
    [ "$(strip "$work/ref.json")" = "$(strip "$work/out0.json")" ] || fail "outside-worker sweep counts differ from the in-process sweep"
    ended_finished "$work/worker1.err" 2 || fail "the outside worker did not serve both points"
    "$bin" sweep "$scene" "${sweep_args[@]}" --workers 1 --lcm "$url" > "$work/out.json" 2> "$work/sweep.err" ||
      fail "dicesim sweep --workers exited $?"
    [ "$(strip "$work/ref.json")" = "$(strip "$work/out.json")" ] || fail "distributed sweep counts differ from the in-process sweep"
    [ "$(jq '.points | length' "$work/out.json")" = 2 ] || fail "expected 2 points"
    [ "$(jq '.workers' "$work/out.json")" = 1 ] || fail "workers should report the 1 local worker"
    echo "outside worker ended $(grep -c "ended: finished" "$work/worker1.err") of 4 points' runs"
    sleep 0.2
    if pgrep -f -- "--lcm $url --quiet" > /dev/null; then fail "local worker processes left behind"; fi
    ;;
  interrupt)
    # Ctrl-C on `dicesim run`: exit 1, no result on stdout, no worker left behind.
    url="udpm://239.255.76.67:$((30000 + $$ % 20000))?ttl=0"
    "$bin" run "$scene" --workers 2 --tosses 50000000 --seed "$seed" --json --lcm "$url" > "$work/out.json" 2> "$work/run.err" &
    run=$!
    LCM_DEFAULT_URL=$url "$inject" progress 0.0001 60 || fail "the run did not start"
    kill -INT "$run"
    code=0
    wait "$run" || code=$?
    [ "$code" -eq 1 ] || fail "an interrupted run exited $code, expected 1"
    [ ! -s "$work/out.json" ] || fail "an interrupted run printed a result"
    grep -q "interrupted" "$work/run.err" || fail "no 'interrupted' on stderr"
    sleep 0.2
    if pgrep -f -- "--lcm $url" > /dev/null; then fail "worker processes left behind"; fi
    ;;
  target)
    n=1000000
    h=0.004  # about 35 000 tosses: a few blocks of 10 000
    "$bin" toss "$scene" --seed "$seed" --threads 2 --json --target-halfwidth $h > "$work/ref.json" 2> "$work/ref.err"
    "$bin" toss "$scene" --seed "$seed" --threads 1 --json --target-halfwidth $h > "$work/ref1.json" 2>/dev/null
    [ "$(stable "$work/ref.json")" = "$(stable "$work/ref1.json")" ] || fail "toss --target-halfwidth depends on threads"
    took=$(grep -oE '"tosses":[0-9]+' "$work/ref.json" | tail -n1 | grep -oE '[0-9]+')  # the last: the run's, after provenance's
    [ "$took" -gt 10000 ] && [ $((took % 10000)) -eq 0 ] || fail "target stop $took is not a later block boundary"
    "$bin" run "$scene" --workers 2 --seed "$seed" --json --target-halfwidth $h > "$work/out.json" 2> "$work/run.err" ||
      fail "dicesim run exited $?"
    same_as_reference "$work/out.json"
    echo "target half-width $h: $took tosses in toss and in run"
    grep -q "reached after" "$work/run.err" || fail "run does not report how many tosses the target took"
    ;;
  trace)
    n=3000
    reference
    "$inject" count DICESIM_BOUNCE_STATE 120 > "$work/count.out" & counter=$!; pids+=($counter)
    sleep 0.5
    worker
    aggregate --trace-every 100 || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    sleep 0.3
    kill -TERM "$counter"; wait "$counter" || true
    traced=$(cat "$work/count.out")
    echo "bounce_state messages received: $traced"
    [ "${traced:-0}" -gt 0 ] || fail "no bounce states published with --trace-every"
    ;;
  forgery)
    # An authenticated run (--key-file everywhere) and a forger who knows the run id but not the
    # key: batches claiming face 6 for every index (before the workers get there), with no seal,
    # with a wrong key's seal, and genuine batches with faces changed; "finished" answers and a
    # run_start with another seed for the workers. Counts identical; every forgery dropped and counted.
    n=300000
    reference
    key=$work/run.key
    (umask 077; od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$key")
    "$bin" record -o "$work/run.lcmlog" --until-done --timeout 120 --key-file "$key" 2> "$work/rec.err" & rec=$!; pids+=($rec)
    for _ in $(seq 100); do grep -q "dicesim record: recording" "$work/rec.err" && break; sleep 0.1; done
    "$inject" forge > "$work/forge.out" 2> "$work/forge.err" & forger=$!; pids+=($forger)
    aggregate --key-file "$key" & agg=$!
    # Workers only once every index has been claimed by forged batches: without the HMAC check the
    # aggregator would have had the whole run from the forger (all face 6) before any real result.
    for _ in $(seq 300); do grep -q "forged batches" "$work/forge.out" && break; sleep 0.1; done
    grep -q "forged batches" "$work/forge.out" || fail "the forger never forged"
    worker --key-file "$key"; worker --key-file "$key"
    wait "$agg" || fail "aggregate exited $?"
    same_as_reference "$work/out.json"
    wait "$forger" || fail "the forger failed: $(cat "$work/forge.err")"
    cat "$work/forge.out"
    sent=$(( $(grep "forged batches" "$work/forge.out" | grep -oE '[0-9]+' | paste -sd+) ))  # no bc: not in every image
    got=$(health unauthenticated "$work/agg.err")
    echo "forged batches sent before the workers started: $sent; unauthenticated messages dropped by the aggregator: $got"
    # The aggregator hears every channel, so every forgery (LCM over loopback loses none here).
    [ "$got" -ge "$sent" ] || fail "the aggregator counted $got unauthenticated messages of $sent forged"
    for k in 1 2; do
      wait "${wpid[$k]}" || fail "worker $k exited $?"
      grep -qE "ended: finished \([1-9][0-9]* tosses" "$work/worker$k.err" || fail "worker $k did no tosses (stopped by a forgery?)"
      grep -qE "dropped [1-9][0-9]* messages that failed the HMAC check" "$work/worker$k.err" || fail "worker $k counted no forgeries"
    done
    wait "$rec" || fail "dicesim record --key-file exited $?"
    # The log holds the forgeries too (a recorder writes what it hears): replay --key-file drops them.
    "$bin" replay "$work/run.lcmlog" --key-file "$key" --json > "$work/replay.json" 2> "$work/replay.err" ||
      fail "replay --key-file exited $?"
    same_as_reference "$work/replay.json"
    [ "$(health unauthenticated "$work/replay.err")" -ge "$sent" ] || fail "replay did not drop the recorded forgeries"
    code=0; "$bin" replay "$work/run.lcmlog" --json > /dev/null 2> "$work/nokey.err" || code=$?
    [ "$code" -eq 2 ] && grep -q "replay it with --key-file" "$work/nokey.err" || fail "replay without the key: exit $code, $(cat "$work/nokey.err")"
    (umask 077; od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$work/other.key")
    code=0; "$bin" replay "$work/run.lcmlog" --key-file "$work/other.key" --json > /dev/null 2> "$work/otherkey.err" || code=$?
    [ "$code" -eq 2 ] || fail "replay with another key: exit $code"
    ;;
  agg_restart)
    # The aggregator itself dies (kill -9) mid-run and is resumed from its checkpoint: the same run
    # id, the same two workers (never restarted), counts identical to toss; a recorder across the
    # restart gives a log that replays to the same counts and says how many tosses were computed twice.
    # 4*10^6 tosses: the aggregator checkpoints at most once a second, so the first checkpoint
    # holding tosses comes ~1 s in; 10^6 paper tosses on two workers took ~1.2 s, and under load the
    # kill once landed after the run had finished (the workers gone, the resume waited for them).
    n=4000000
    reference
    ckpt=$work/run.ckpt
    "$bin" record -o "$work/run.lcmlog" --until-done --timeout 150 2> "$work/rec.err" & rec=$!; pids+=($rec)
    for _ in $(seq 100); do grep -q "dicesim record: recording" "$work/rec.err" && break; sleep 0.1; done
    worker; worker
    t0=$(date +%s%N)
    "$bin" aggregate "$scene" --tosses "$n" --seed "$seed" --json --timeout 150 --checkpoint "$ckpt" \
      > "$work/first.json" 2> "$work/agg1.err" & agg1=$!; pids+=($agg1)
    # The first checkpoint (written at once) holds no toss; kill after one that does.
    held() { jq '[.received[] | .[1] - .[0]] | add // 0' "$ckpt" 2> /dev/null || echo 0; }
    for _ in $(seq 300); do [ -s "$ckpt" ] && [ "$(held)" -gt 0 ] && break; sleep 0.02; done
    [ "$(held)" -gt 0 ] || fail "no checkpoint holding tosses was written"
    kill -9 "$agg1"; wait "$agg1" 2> /dev/null || true
    tk=$(date +%s%N)
    echo "killed the aggregator; its last checkpoint holds $(held) of $n tosses"
    "$bin" aggregate --resume "$ckpt" --json --timeout 150 > "$work/out.json" 2> "$work/agg.err" || fail "aggregate --resume exited $?"
    t1=$(date +%s%N)
    same_as_reference "$work/out.json"
    [ ! -s "$work/first.json" ] || fail "the killed aggregator printed a result"
    grep -h "resumed run\|checkpoint '" "$work/agg.err" || fail "no report of what the resume found"
    grep -q "checkpoint '$ckpt'" "$work/agg.err" || fail "no checkpoint cost line"
    for k in 1 2; do
      wait "${wpid[$k]}" || fail "worker $k exited $?"
      [ "$(grep -c "ended:" "$work/worker$k.err")" = 1 ] && grep -qE "ended: finished \([1-9][0-9]* tosses" "$work/worker$k.err" ||
        fail "worker $k did not serve the run through the restart"
    done
    wait "$rec" || fail "dicesim record exited $?"
    "$bin" replay "$work/run.lcmlog" --json > "$work/replay.json" 2> "$work/replay.err" || fail "replay exited $?"
    same_as_reference "$work/replay.json"
    twice=$(grep -oE '\(([0-9]+) more than once' "$work/replay.err" | grep -oE '[0-9]+')
    # Bound: the work done after the checkpoint the resume read was taken — its age at the resume
    # (about one checkpoint interval plus the restart gap; more when fsync is slow) — plus one
    # interval of slack for the rate's ups and downs, plus the leases the workers had queued
    # (2 each, at most AggregatorConfig::max_lease = 32768 tosses), at the run's average throughput.
    rate=$((n * 1000000000 / (t1 - t0)))
    age_ms=$(grep -oE 'checkpoint [0-9.]+ s old' "$work/agg.err" | grep -oE '[0-9.]+' | awk '{ printf "%d", $1 * 1000 }')
    bound=$((rate * (age_ms + 1000) / 1000 + 2 * 2 * 32768))
    echo "aggregator killed and resumed: $twice tosses computed twice (bound $bound: checkpoint $age_ms ms old at the resume + 1 s, at $rate tosses/s, + queued leases)"
    [ -n "$twice" ] && [ "$twice" -le "$bound" ] || fail "tosses computed twice: '$twice', more than $bound"
    ;;
  *) echo "unknown scenario $scenario" >&2; exit 2 ;;
esac
[ -f "$work/agg.err" ] && grep -h "batches" "$work/agg.err"
echo "PASS [$scenario]"
