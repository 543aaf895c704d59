#!/usr/bin/env bash
# Soak (not CI; root, for a private network namespace): a long distributed run under trouble.
# W `dicesim worker` processes and `dicesim aggregate --checkpoint` run N paper tosses of Die 1 while
# nftables drops 5% of all packets at random; every K seconds one worker is killed (kill -9) and a
# new one started in its place; once, at A seconds, the aggregator itself is killed (kill -9) and
# resumed from its checkpoint (`aggregate --resume`). Reports the resident memory of every process
# every second (CSV, and a summary: does anything grow?), re-leased tosses, dropped packets, and
# checks that the final counts equal `dicesim toss` (the issue's scale is N=10^8, W=8, K=10; on
# a shared 2-core machine that is about 4 to 8 minutes of tossing plus the reference).
#   bench/soak.sh [DICESIM] [N] [W] [K] [A]     defaults: build/apps/dicesim 100000000 8 10 (N-dependent)
# Memory samples stay in $SOAK_OUT (default /tmp/dicesim-soak.csv): t_s,role,pid,rss_kb.
set -euo pipefail
. "$(dirname "$0")/private_net.sh" "$@"

cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/apps/dicesim}")
n=${2:-100000000}
nworkers=${3:-8}
every=${4:-10}
agg_kill_at=${5:-$((n / 4000000 > 20 ? n / 4000000 : 20))}  # about a quarter of the way on 2 cores
out_csv=${SOAK_OUT:-/tmp/dicesim-soak.csv}
scene=scenes/paper/die1.toml seed=1
url="udpm://239.255.76.67:7667?ttl=0"
work=$(mktemp -d /tmp/dicesim-soak-XXXXXX)
declare -a wpid
agg=""
sampler=""
cleanup() {
  for p in "${wpid[@]}" $agg $sampler; do kill -9 "$p" 2> /dev/null || true; done
  wait 2> /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

# 5% of every packet on every port, in and out of every process here, dropped at random.
nft add table inet soak
nft add chain inet soak input '{ type filter hook input priority 0; policy accept; }'
nft add rule inet soak input numgen random mod 20 0 counter drop

# The processes to sample, one "role pid" per line, rewritten whenever one changes.
note_pids() {
  { for k in "${!wpid[@]}"; do echo "worker ${wpid[$k]}"; done; [ -n "$agg" ] && echo "aggregator $agg"; } > "$work/pids.tmp"
  mv "$work/pids.tmp" "$work/pids"
}
start_worker() {  # start_worker SLOT
  "$bin" worker --lcm "$url" --quiet 2>> "$work/worker$1.err" &
  wpid[$1]=$!
  note_pids
}
start_aggregator() {  # start_aggregator ARGS...: output in agg$k.json / agg$k.err
  local k=$1
  shift
  "$bin" aggregate "$@" --lcm "$url" --json > "$work/agg$k.json" 2> "$work/agg$k.err" &
  agg=$!
  note_pids
}
echo "soak: $n tosses, $nworkers workers, 5% packet loss, a worker killed every ${every} s, the aggregator at ${agg_kill_at} s"
for k in $(seq "$nworkers"); do start_worker "$k"; done
t0=$(date +%s%N)
start_aggregator 1 "$scene" --tosses "$n" --seed "$seed" --checkpoint "$work/soak.ckpt"

# Memory of every process, every second: VmRSS from /proc/PID/status, read without forking (the
# machine may be busy; a fork per sample would make the sampler late).
(
  echo "t_s,role,pid,rss_kb"
  start=${EPOCHREALTIME%.*}
  while :; do
    t=$(( ${EPOCHREALTIME%.*} - start ))
    while read -r role p; do
      rss=""
      while read -r k v _; do
        if [ "$k" = "VmRSS:" ]; then rss=$v; break; fi
      done 2> /dev/null < "/proc/$p/status" || true
      [ -n "$rss" ] && echo "$t,$role,$p,$rss"
    done < "$work/pids"
    sleep 1
  done
) > "$out_csv" &
sampler=$!

victim=1 resumed=0 kills=0
while kill -0 "$agg" 2> /dev/null; do
  sleep "$every" &
  wait $! || true
  kill -0 "$agg" 2> /dev/null || break
  now=$(( ($(date +%s%N) - t0) / 1000000000 ))
  if [ "$resumed" -eq 0 ] && [ "$now" -ge "$agg_kill_at" ]; then
    kill -9 "$agg"; wait "$agg" 2> /dev/null || true
    echo "soak: t=${now}s aggregator killed (kill -9); resuming from its checkpoint"
    start_aggregator 2 --resume "$work/soak.ckpt"
    resumed=1
    continue
  fi
  kill -9 "${wpid[$victim]}" 2> /dev/null || true
  wait "${wpid[$victim]}" 2> /dev/null || true
  start_worker "$victim"
  kills=$((kills + 1))
  echo "soak: t=${now}s worker $victim killed (kill -9) and started again"
  victim=$((victim % nworkers + 1))
done
code=0
wait "$agg" || code=$?
t1=$(date +%s%N)
kill "$sampler" 2> /dev/null || true
last=$([ "$resumed" -eq 1 ] && echo 2 || echo 1)
[ "$code" -eq 0 ] || { tail -n 20 "$work/agg$last.err" >&2; echo "soak: FAILED: the aggregator exited $code" >&2; exit 1; }
echo "soak: run finished in $(( (t1 - t0) / 1000000 )) ms ($kills worker kills, aggregator resumed: $resumed)"
grep -h "resumed run\|checkpoint '\|batches" "$work"/agg*.err | sed -E 's/^\[[^]]*\] \[[a-z]+\] \[[^]]*\] /  /'
dropped=$(nft list chain inet soak input | grep -oE 'packets [0-9]+' | grep -oE '[0-9]+')
echo "soak: packets dropped by nftables: $dropped"

# Memory: per role, the largest RSS, and the aggregator's over time (first, middle, last sample).
awk -F, 'NR > 1 { if ($4 > max[$2]) max[$2] = $4; n[$2]++ }
         END { for (r in max) printf "soak: %s max RSS %.1f MB over %d samples\n", r, max[r] / 1024, n[r] }' "$out_csv"
awk -F, '$2 == "aggregator" { t[++k] = $1; r[k] = $4 }
         END { if (k) printf "soak: aggregator RSS at t=%ds %.1f MB, t=%ds %.1f MB, t=%ds %.1f MB\n",
                 t[1], r[1] / 1024, t[int((k + 1) / 2)], r[int((k + 1) / 2)] / 1024, t[k], r[k] / 1024 }' "$out_csv"
awk -F, '$2 == "worker" { t = $1 + 0; if (!(t in by) || $4 > by[t]) by[t] = $4; if (f == "" || t < f) f = t; if (t > l) l = t }
         END { if (f != "") printf "soak: largest worker RSS at t=%ds %.1f MB, at t=%ds %.1f MB\n", f, by[f] / 1024, l, by[l] / 1024 }' "$out_csv"
echo "soak: memory samples in $out_csv"

echo "soak: reference: dicesim toss --threads 2 (about $((n / 900000)) s)"
"$bin" toss "$scene" --tosses "$n" --seed "$seed" --threads 2 --json > "$work/ref.json"
strip() { sed -E 's/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//; s/"tosses_per_s":[^,}]*,?//' "$1"; }
if [ "$(strip "$work/ref.json")" = "$(strip "$work/agg$last.json")" ]; then
  echo "soak: PASS: final counts identical to dicesim toss"
else
  echo "toss: $(strip "$work/ref.json")" >&2
  echo "soak: $(strip "$work/agg$last.json")" >&2
  echo "soak: FAILED: counts differ" >&2
  exit 1
fi
