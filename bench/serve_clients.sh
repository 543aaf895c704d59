#!/usr/bin/env bash
# `dicesim serve`'s CPU with N clients on its page's event stream during a run (reported, not a
# test; issue 37's target: 10 browsers at <= 5 % of one core while it keeps its 4 Hz updates), in
# a private network namespace made here (root needed).
#   bench/serve_clients.sh [BUILD_DIR] [CLIENTS] [SECONDS] [curl|chromium] [SERVE ARGS...]
#   (default: build 10 20 curl)
# A `dicesim run` of Die 1 with one worker goes on for the whole measurement; CLIENTS clients
# hold /events open (curl -N: the stream a browser's EventSource reads; chromium: headless pages
# of the live page itself, each its own browser). After 3 s of warm-up, serve's CPU is its
# utime + stime from /proc/PID/stat over SECONDS, as a share of one core; the events one client
# received in that window give the update rate. Then the same without clients, for comparison.
set -euo pipefail
bad() { sed -n '5,6p' "$0" | sed 's/^#  *//' >&2; echo "$(basename "$0"): $1" >&2; exit 2; }
# (As the script uses it below: from the repository's root; an absolute path as it is.)
(cd "$(dirname "$0")/.." && [ -x "${1:-build}/apps/dicesim" ]) ||
  bad "no apps/dicesim in BUILD_DIR '${1:-build}' (a build directory, relative to the repository)"
[[ ${2:-10} =~ ^[1-9][0-9]*$ ]] || bad "CLIENTS must be a positive integer, not '${2}'"
[[ ${3:-20} =~ ^[1-9][0-9]*$ ]] || bad "SECONDS must be a positive integer, not '${3}'"
[[ ${4:-curl} =~ ^(curl|chromium)$ ]] || bad "the client kind must be curl or chromium, not '${4}'"
. "$(dirname "$0")/private_net.sh" "$@"
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"
cd "$(dirname "$0")/.."
build=${1:-build}
clients=${2:-10}
window=${3:-20}
kind=${4:-curl}
extra=("${@:5}")
bin=$build/apps/dicesim
port=18050
work=$(mktemp -d /tmp/dicesim-bench-serve-XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -9 -- "-$p" 2> /dev/null || kill -9 "$p" 2> /dev/null || true; wait "$p" 2> /dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT

"$bin" serve --port $port "${extra[@]}" 2> "$work/serve.err" & serve=$!
pids+=($serve)
for _ in $(seq 100); do curl -sf "http://127.0.0.1:$port/state" > /dev/null && break; sleep 0.1; done
"$bin" run scenes/paper/die1.toml --workers 1 --tosses 2000000000 --seed 1 --lcm "$LCM_DEFAULT_URL" > /dev/null 2> "$work/run.err" &
pids+=($!)
sleep 2  # the run's first answers

ticks() { awk '{print $14 + $15}' "/proc/$serve/stat"; }
measure() {  # measure LABEL: serve's CPU over the window, and one client's events in it
  sleep 3
  local e0 t0 e1 t1 n0 n1 conns
  conns=$(ss -Htn state established "( sport = :$port )" | wc -l)
  n0=$(grep -c '^data: ' "$work/client-0.txt" 2> /dev/null || true)
  t0=$(ticks)
  e0=$(date +%s.%N)
  sleep "$window"
  t1=$(ticks)
  e1=$(date +%s.%N)
  n1=$(grep -c '^data: ' "$work/client-0.txt" 2> /dev/null || true)
  awk -v l="$1" -v t="$((t1 - t0))" -v hz="$(getconf CLK_TCK)" -v s0="$e0" -v s1="$e1" -v n="$(( ${n1:-0} - ${n0:-0} ))" \
    -v c="$conns" 'BEGIN { w = s1 - s0; printf "%s (%d connections open): serve used %.2f %% of one core over %.1f s (%d ticks of 1/%d s)", l, c, 100 * t / hz / w, w, t, hz;
             if (n > 0) printf "; one client got %.2f events/s", n / w; printf "\n" }'
}

client_pids=()
for i in $(seq 0 $((clients - 1))); do
  if [ "$kind" = chromium ]; then
    # The page's own stream is not visible from outside; a curl client beside them counts events.
    # Its own process group (setsid), killed whole: the browser's helpers with it.
    setsid chromium --headless=new --no-sandbox --disable-gpu --no-first-run --no-default-browser-check \
      --disable-background-networking --disable-component-update --disable-sync --disable-extensions \
      --user-data-dir="$work/profile-$i" --remote-debugging-port=$((19300 + i)) "http://127.0.0.1:$port/" > /dev/null 2>&1 &
    sleep 1  # one at a time: ten starting at once swamp two cores
  else
    curl -sN "http://127.0.0.1:$port/events" > "$work/client-$i.txt" &
  fi
  client_pids+=($!)
  pids+=($!)
done
[ "$kind" = chromium ] && { curl -sN "http://127.0.0.1:$port/events" > "$work/client-0.txt" & pids+=($!); client_pids+=($!); }
# Every client connected (a browser takes seconds to start) before the window opens.
want=$clients; [ "$kind" = chromium ] && want=$((clients + 1))  # and the counting curl
for _ in $(seq 120); do
  [ "$(ss -Htn state established "( sport = :$port )" | wc -l)" -ge "$want" ] && break
  sleep 0.5
done
echo "load before: $(uptime)"
measure "$clients $kind clients"
for p in "${client_pids[@]}"; do kill -9 -- "-$p" 2> /dev/null || kill -9 "$p" 2> /dev/null || true; wait "$p" 2> /dev/null || true; done
rm -f "$work/client-0.txt"
curl -sN "http://127.0.0.1:$port/events" > "$work/client-0.txt" & pids+=($!)
measure "1 curl client (baseline)"
echo "load after: $(uptime)"
