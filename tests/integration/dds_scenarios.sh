#!/usr/bin/env bash
# The LCM -> DDS bridge with real processes, each scenario inside a private network namespace
# this script creates (only loopback: nothing can leave it). Run by CTest, one scenario per test:
#   dds_scenarios.sh DICESIM_BINARY DDS_SUBSCRIBER_BINARY LCM_INJECT_BINARY SCENARIO
# Scenarios: late_subscriber final_values restart replay authenticated (tests/integration/README.md).
# The bridge finds its loopback configuration by itself (bridge/cyclonedds-loopback.xml next to
# the build); the example subscriber is pointed at the same file with CYCLONEDDS_URI.
set -euo pipefail

. "$(dirname "$0")/private_net.sh" dds "$@"

bin=$1 sub=$2 inject=$3 scenario=$4

scene=scenes/paper/die1.toml
seed=11
# A scenario name ending in _d20 or _d4 runs the same scenario on that die (scenes/dice/):
# everything that works for a d6 works for any number of outcomes.
# Those state `paper`, the model they ran before `auto` became the default: this tests the bridge,
# and 3e6 `impulse` d20 tosses would not fit the run's timeout.
model=()
case "$scenario" in
  *_d20) scene=scenes/dice/d20.toml; scenario=${scenario%_d20}; model=(--fidelity paper) ;;
  *_d4) scene=scenes/dice/d4.toml; scenario=${scenario%_d4}; model=(--fidelity paper) ;;
esac
echo "scenario $scenario on $scene"
fail() {
  echo "FAIL [$scenario]: $*" >&2
  for f in "$work"/*.err "$work"/*.jsonl; do [ -f "$f" ] && { echo "--- $f" >&2; tail -n 15 "$f" >&2; }; done
  exit 1
}

# The subscriber, as any external program would run it (only the config file from the repo).
# Started with `&`, it runs in a subshell: exec there, so that the pid in $! (killed at exit) is
# the subscriber itself and none is left running after the script.
subscriber() {
  if [ "$BASHPID" != "$$" ]; then CYCLONEDDS_URI="file://$src_dir/bridge/cyclonedds-loopback.xml" exec "$sub" --json "$@"; fi
  CYCLONEDDS_URI="file://$src_dir/bridge/cyclonedds-loopback.xml" "$sub" --json "$@"
}
bridge() { "$bin" bridge "$@" 2> "$work/bridge.err" & bridge_pid=$!; pids+=($bridge_pid); }
nworkers=0
worker() { nworkers=$((nworkers + 1)); "$bin" worker "$@" 2> "$work/worker$nworkers.err" & pids+=($!); }

# Run ids are 63-bit: jq would round them to doubles, so they are read as text.
run_id() { grep -oE '"run_id":-?[0-9]+' | head -n1 | cut -d: -f2; }
# The finished answer of run $2 in subscriber output $1 equals the aggregator's JSON $3:
# identical counts, and p and the 95% interval identical to the last bit.
same_as_json() {
  local line
  line=$(grep '"topic":"dicesim_probabilities"' "$1" | grep -F "\"run_id\":$2," | grep '"finished":true' | tail -n1)
  [ -n "$line" ] || fail "no finished answer of run $2 in $1"
  echo "$line" > "$work/dds_final.json"
  jq -e --slurpfile d "$work/dds_final.json" '
      $d[0] as $d
      | .settled == $d.settled and .unresolved == $d.unresolved and .invalid == $d.invalid
        and .tosses == $d.done and ([.faces[] | [.face, .count, .p, .ci95]] == [$d.faces[] | [.face, .count, .p, .ci95]])
        and (.provenance | {version, scene, scene_sha256, overrides, fidelity, seed, tosses})
            == ($d.provenance | {version, scene, scene_sha256, overrides, fidelity, seed, tosses})' \
      "$3" > /dev/null || { echo "aggregator: $(jq -c '{settled, unresolved, invalid, faces}' "$3")" >&2;
                            echo "over DDS:   $(cat "$work/dds_final.json")" >&2;
                            fail "values over DDS differ from the aggregator's JSON"; }
}
# The bridge stops cleanly on a signal: exit 0 within 2 s, with its summary line.
stops_cleanly() {
  kill "-$1" "$bridge_pid"
  for _ in $(seq 20); do kill -0 "$bridge_pid" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$bridge_pid" 2>/dev/null && fail "bridge still running 2 s after SIG$1"
  local code=0; wait "$bridge_pid" || code=$?
  [ "$code" -eq 0 ] || fail "bridge exited $code after SIG$1"
  grep -q "bridge stopped" "$work/bridge.err" || fail "no summary line from the bridge"
}

case "$scenario" in
  late_subscriber)
    # A subscriber that joins mid-run gets the run's latest answer within 2 s; one that joins
    # after the run ended (nobody publishes any more) still gets the final answer: transient-local.
    n=3000000
    bridge
    worker --once; worker --once
    "$bin" aggregate "$scene" "${model[@]}" --tosses $n --seed $seed --json --timeout 150 > "$work/agg.json" 2> "$work/agg.err" & agg=$!
    pids+=($agg)
    "$inject" progress 0.1 60 || fail "the run never reached 10%, or finished first"
    start=$(date +%s%N)
    subscriber --topic probabilities --count 1 --timeout 2 > "$work/late.jsonl" || fail "mid-run subscriber: no answer within 2 s"
    took_ms=$(( ($(date +%s%N) - start) / 1000000 ))
    jq -e --argjson n $n '.done >= 0.1 * $n and .total == $n' "$work/late.jsonl" > /dev/null ||
      fail "the mid-run answer is not the run's latest (done < 10%): $(cat "$work/late.jsonl")"
    echo "mid-run subscriber: first answer after $took_ms ms (process start included), done $(jq .done "$work/late.jsonl") of $n"
    wait "$agg" || fail "aggregate exited $?"
    run=$(run_id < "$work/late.jsonl")
    sleep 0.5
    start=$(date +%s%N)
    subscriber --topic probabilities --until-finished --timeout 2 > "$work/after.jsonl" ||
      fail "subscriber started after the run: no finished answer within 2 s"
    took_ms=$(( ($(date +%s%N) - start) / 1000000 ))
    echo "subscriber after the run: final answer after $took_ms ms"
    same_as_json "$work/after.jsonl" "$run" "$work/agg.json"
    stops_cleanly INT
    ;;
  final_values)
    # `dicesim run --json` (its own LCM port) and a subscriber listening all along: the last
    # answer over DDS is the printed result; the status topic saw the run through to finished.
    url="udpm://239.255.76.67:$((30000 + $$ % 20000))?ttl=0"
    bridge --lcm "$url"
    subscriber --until-finished --timeout 120 > "$work/live.jsonl" 2> "$work/sub.err" & subp=$!; pids+=($subp)
    "$bin" watch --lcm "$url" --until-finished --timeout 120 > "$work/watch.out" 2> "$work/watch.err" & watchp=$!; pids+=($watchp)
    sleep 0.5
    "$bin" run "$scene" --workers 2 --tosses 400000 --seed $seed --json --lcm "$url" > "$work/run.json" 2> "$work/run.err" ||
      fail "dicesim run exited $?"
    wait "$subp" || fail "subscriber exited $? (no finished answer)"
    run=$(grep '"topic":"dicesim_probabilities"' "$work/live.jsonl" | tail -n1 | run_id)
    same_as_json "$work/live.jsonl" "$run" "$work/run.json"
    answers=$(grep -c '"topic":"dicesim_probabilities"' "$work/live.jsonl")
    echo "answers received live: $answers"
    # `dicesim watch` (the CLI way to watch) saw the same run to its end.
    wait "$watchp" || fail "dicesim watch exited $?"
    grep -q "^run $run  FINISHED 400000/400000" "$work/watch.out" || fail "dicesim watch did not print the finished run"
    sha=$(jq -r .provenance.scene_sha256 "$work/run.json")
    grep -q "^run $run provenance: .*\"scene_sha256\":\"$sha\"" "$work/watch.out" ||
      fail "dicesim watch did not print the run's provenance (scene sha256 $sha)"
    sleep 0.3
    subscriber --topic status --count 1 --timeout 2 > "$work/status.jsonl" || fail "no run status"
    grep -qF "\"run_id\":$run," "$work/status.jsonl" || fail "run status of another run: $(cat "$work/status.jsonl")"
    jq -e --arg scene "$scene" '.state == "finished" and .origin == $scene and .seed == 11 and .total_tosses == 400000' \
      "$work/status.jsonl" > /dev/null || fail "run status is not finished/complete: $(cat "$work/status.jsonl")"
    stops_cleanly TERM
    ;;
  restart)
    # An aggregator killed mid-run (kill -9), then a new run with a new id on the same bus:
    # the bridge keeps going, marks the dead run silent, publishes the new run to the end, and
    # a late subscriber sees both runs' latest answers (one instance per run id).
    bridge
    worker; worker  # long-lived workers: they serve both runs
    subscriber > "$work/all.jsonl" 2> "$work/sub.err" & pids+=($!)
    "$bin" aggregate "$scene" --tosses 50000000 --seed 5 --json > /dev/null 2> "$work/agg1.err" & agg1=$!; pids+=($agg1)
    "$inject" progress 0.002 60 || fail "the first run never started"
    kill -9 "$agg1"
    sleep 0.3
    run1=$(grep '"topic":"dicesim_probabilities"' "$work/all.jsonl" | head -n1 | run_id)
    [ -n "$run1" ] || fail "no answer of the first run over DDS"
    "$bin" aggregate "$scene" --tosses 300000 --seed $seed --json --timeout 120 > "$work/agg2.json" 2> "$work/agg2.err" ||
      fail "second aggregate exited $?"
    sleep 0.5
    run2=$(grep '"topic":"dicesim_probabilities"' "$work/all.jsonl" | grep '"finished":true' | tail -n1 | run_id)
    [ -n "$run2" ] || fail "no finished answer of the second run over DDS"
    [ "$run1" != "$run2" ] || fail "the second run has the first one's id"
    kill -0 "$bridge_pid" 2>/dev/null || fail "the bridge died"
    same_as_json "$work/all.jsonl" "$run2" "$work/agg2.json"
    # The first run's aggregator is silent for > 3 s by now (or soon): its status says so.
    for _ in $(seq 40); do
      grep -q "\"run_id\":$run1,[^}]*\"state\":\"silent\"" "$work/all.jsonl" && break
      sleep 0.1
    done
    grep -q "\"run_id\":$run1,[^}]*\"state\":\"silent\"" "$work/all.jsonl" || fail "the killed run was never marked silent"
    grep -q "\"run_id\":$run2,[^}]*\"state\":\"finished\"" "$work/all.jsonl" || fail "the second run's status never said finished"
    subscriber --topic probabilities --count 2 --timeout 2 > "$work/late.jsonl" || fail "late subscriber: not both runs within 2 s"
    [ "$(grep -oE '"run_id":-?[0-9]+' "$work/late.jsonl" | cut -d: -f2 | sort | tr '\n' ' ')" = "$(printf '%s\n' "$run1" "$run2" | sort | tr '\n' ' ')" ] ||
      fail "late subscriber did not get one latest answer per run: $(cat "$work/late.jsonl")"
    echo "runs $run1 (killed) and $run2 (finished) both on DDS"
    stops_cleanly TERM
    ;;
  replay)
    # A recorded run replayed at recorded pace (`dicesim replay --live`) drives the bridge to the
    # same final values as the live run printed.
    url="udpm://239.255.76.67:$((30000 + $$ % 20000))?ttl=0"
    "$bin" record --lcm "$url" -o "$work/run.lcmlog" --until-done --timeout 120 2> "$work/record.err" & rec=$!; pids+=($rec)
    sleep 0.5
    "$bin" run "$scene" --workers 2 --tosses 200000 --seed $seed --json --lcm "$url" > "$work/run.json" 2> "$work/run.err" ||
      fail "dicesim run exited $?"
    wait "$rec" || fail "dicesim record exited $?"
    [ -s "$work/run.lcmlog" ] || fail "nothing recorded"
    bridge  # on the default URL: only the replay speaks there
    subscriber --topic probabilities --until-finished --timeout 120 > "$work/replayed.jsonl" 2> "$work/sub.err" & subp=$!; pids+=($subp)
    sleep 0.5
    "$bin" replay "$work/run.lcmlog" --live --speed 2 2> "$work/replay.err" > /dev/null || fail "dicesim replay --live exited $?"
    wait "$subp" || fail "no finished answer over DDS from the replay"
    run=$(tail -n1 "$work/replayed.jsonl" | run_id)
    same_as_json "$work/replayed.jsonl" "$run" "$work/run.json"
    stops_cleanly TERM
    ;;
  authenticated)
    # `bridge --key-file` on an authenticated run, with a forger on the bus (lcm_inject forge): its
    # unsealed and wrong-key "finished" answers must never reach DDS. The subscriber stops at the
    # first finished answer it gets: it must be the real one.
    key=$work/run.key
    (umask 077; od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$key")
    bridge --key-file "$key"
    subscriber --topic probabilities --until-finished --timeout 120 > "$work/sub.jsonl" 2> "$work/sub.err" & subp=$!; pids+=($subp)
    sleep 1  # DDS discovery between bridge and subscriber
    "$inject" forge > "$work/forge.out" 2> "$work/forge.err" & forger=$!; pids+=($forger)
    "$bin" aggregate "$scene" --tosses 300000 --seed $seed --json --timeout 150 --key-file "$key" > "$work/agg.json" 2> "$work/agg.err" & agg=$!
    pids+=($agg)
    for _ in $(seq 300); do grep -q "forged batches" "$work/forge.out" && break; sleep 0.1; done
    worker --once --key-file "$key"; worker --once --key-file "$key"
    wait "$agg" || fail "aggregate exited $?"
    wait "$forger" || fail "the forger failed"
    wait "$subp" || fail "subscriber exited $?"
    run=$(run_id < "$work/sub.jsonl")
    same_as_json "$work/sub.jsonl" "$run" "$work/agg.json"
    stops_cleanly TERM
    got=$(grep -oE '[0-9]+ unauthenticated' "$work/bridge.err" | grep -oE '[0-9]+')
    echo "bridge: $got unauthenticated LCM messages dropped; $(cat "$work/forge.out" | tr '\n' ' ')"
    [ "${got:-0}" -gt 0 ] || fail "the bridge counted no forgeries"
    ;;
  *) echo "unknown scenario $scenario" >&2; exit 2 ;;
esac
echo "PASS [$scenario]"
