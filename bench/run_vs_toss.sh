#!/usr/bin/env bash
# Does the distributed path keep up with the in-process one? Times `dicesim toss --threads W` and
# `dicesim run --workers W` (wall clock, whole command) on the same scene, seed and N, alternating,
# R rounds, and prints each pair's ratio toss_time / run_time (1.0: as fast) and the median, plus
# the load average. `run` opens LCM: the script re-runs itself in a private network namespace
# (root). Usage: bench/run_vs_toss.sh [DICESIM] [N] [W] [R] [SCENE]
set -euo pipefail
. "$(dirname "$0")/private_net.sh" "$@"
DICESIM=${1:-build/apps/dicesim}
N=${2:-1000000}
W=${3:-2}
R=${4:-3}
SCENE=${5:-scenes/paper/die1.toml}

now() { date +%s.%N; }
ratios=()
for ((r = 1; r <= R; r++)); do
  t0=$(now); "$DICESIM" toss "$SCENE" -n "$N" -j "$W" --json > /tmp/dicesim-rvt-toss.json; t1=$(now)
  "$DICESIM" run "$SCENE" -n "$N" --workers "$W" --json > /tmp/dicesim-rvt-run.json 2>/dev/null
  t2=$(now)
  toss_s=$(echo "$t1 - $t0" | bc -l); run_s=$(echo "$t2 - $t1" | bc -l)
  ratio=$(echo "$toss_s / $run_s" | bc -l)
  ratios+=("$ratio")
  printf 'round %d: toss %.3f s, run %.3f s, ratio %.3f  (%s)\n' "$r" "$toss_s" "$run_s" "$ratio" "$(cut -d' ' -f1-3 /proc/loadavg)"
done
median=$(printf '%s\n' "${ratios[@]}" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}')
printf 'N %s, %s workers/threads: median ratio toss/run %.3f over %d rounds; load %s\n' "$N" "$W" "$median" "$R" "$(cut -d' ' -f1-3 /proc/loadavg)"
