#!/usr/bin/env bash
# Bridge latency benchmark (reported, not a test): aggregator publish on LCM -> DDS subscriber
# receipt, on loopback, in a private network namespace made here (root needed).
#   bench/bridge_latency.sh [BUILD_DIR] [SAMPLES]          (default: build, 2000)
# 1. dicesim_bridge_latency plays the aggregator: SAMPLES answers at 200 Hz, each timed to its
#    arrival over DDS on one steady clock (median, p95, p99, max).
# 2. Cross-check with the real aggregator: a `dicesim run` (4 answers/s) watched by the example
#    subscriber; latency = receipt wall clock - the answer's utime (same host, same clock).
set -euo pipefail
bad() { sed -n '4p' "$0" | sed 's/^#  *//' >&2; echo "$(basename "$0"): $1" >&2; exit 2; }
# (As the script uses it below: from the repository's root; an absolute path as it is.)
(cd "$(dirname "$0")/.." && [ -x "${1:-build}/apps/dicesim" ]) ||
  bad "no apps/dicesim in BUILD_DIR '${1:-build}' (a build directory, relative to the repository)"
[[ ${2:-2000} =~ ^[1-9][0-9]*$ ]] || bad "SAMPLES must be a positive integer, not '${2}'"
. "$(dirname "$0")/private_net.sh" "$@"
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
cd "$(dirname "$0")/.."
build=${1:-build}
samples=${2:-2000}
export CYCLONEDDS_URI="file://$PWD/bridge/cyclonedds-loopback.xml"
work=$(mktemp -d /tmp/dicesim-bench-XXXXXX)
"$build/apps/dicesim" bridge 2> "$work/bridge.err" & bridge=$!
trap 'kill -9 $bridge 2>/dev/null || true; rm -rf "$work"' EXIT

"$build/bench/dicesim_bridge_latency" --samples "$samples" --rate 200

"$build/bridge/examples/dicesim_dds_subscriber" --json --topic probabilities --until-finished --timeout 120 > "$work/sub.jsonl" &
sub=$!
sleep 0.5
"$build/apps/dicesim" run scenes/paper/die1.toml --workers 2 --tosses 6000000 --seed 1 --json --lcm "$LCM_DEFAULT_URL" \
  > /dev/null 2> "$work/run.err"
wait $sub || true
# Only this run's answers (total 6000000): the first line is the synthetic run's, from history.
jq -s -r '[.[] | select(.total == 6000000) | (.rx_utime - .utime) / 1000] | sort as $l | length as $n
          | "real aggregator (dicesim run, 2 workers): \($n) answers, median \($l[($n/2|floor)]) ms, p95 \($l[(($n-1)*0.95|round)]) ms, max \($l[-1]) ms"' \
  "$work/sub.jsonl"
kill -INT $bridge; wait $bridge 2>/dev/null || true
