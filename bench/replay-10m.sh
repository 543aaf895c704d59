#!/usr/bin/env bash
# Replay speed (target: a 10^7-toss log in <= 5 s). Records a real distributed run of N tosses
# (`dicesim run --workers 2`, recorded by `dicesim record --until-done`) inside a private network
# namespace, then times `dicesim replay` on the log (wall clock, best of 3) and checks that the
# replayed JSON equals the live one. Needs root (unshare --net); the run itself takes a while
# (about N / 900 000 s on two idle cores).
#   bench/replay-10m.sh [DICESIM_BINARY] [N] [LOG]     defaults: build/apps/dicesim 10000000 (a temp file)
# With LOG given and already present, the recording is skipped and that log is timed.
set -euo pipefail
. "$(dirname "$0")/private_net.sh" "$@"

cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/apps/dicesim}")
n=${2:-10000000}
work=$(mktemp -d /tmp/dicesim-replay-bench-XXXXXX)
trap 'rm -rf "$work"' EXIT
log=${3:-$work/run.lcmlog}
url="udpm://239.255.76.67:7667?ttl=0"

if [ ! -s "$log" ]; then
  "$bin" record --lcm "$url" -o "$log" --until-done --timeout 3600 2> "$work/record.err" & rec=$!
  for _ in $(seq 100); do grep -q "dicesim record: recording" "$work/record.err" && break; sleep 0.1; done
  start=$(date +%s%N)
  "$bin" run scenes/paper/die1.toml --workers 2 --tosses "$n" --seed 1 --lcm "$url" --json > "$work/live.json"
  end=$(date +%s%N)
  wait "$rec"
  echo "live run: $(( (end - start) / 1000000 )) ms for $n tosses"
fi
echo "log: $(stat -c %s "$log") bytes"
best=""
for i in 1 2 3; do
  start=$(date +%s%N)
  "$bin" replay "$log" --json > "$work/replay.json" 2> "$work/replay.err"
  end=$(date +%s%N)
  t=$(( (end - start) / 1000000 ))
  echo "replay $i: $t ms"
  if [ -z "$best" ] || [ "$t" -lt "$best" ]; then best=$t; fi
done
grep -E "read [0-9]+ events" "$work/replay.err" || true
if [ -s "$work/live.json" ]; then
  strip() { sed -E 's/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//; s/"tosses_per_s":[^,}]*,?//' "$1"; }
  [ "$(strip "$work/live.json")" = "$(strip "$work/replay.json")" ] && echo "replay JSON == live JSON" ||
    { echo "replay JSON differs from the live run" >&2; exit 1; }
fi
echo "best replay: $best ms ($(grep -oE '"tosses":[0-9]+' "$work/replay.json"))"
