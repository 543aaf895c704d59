#!/usr/bin/env bash
# Does the distributed path keep up with the in-process one (issue 14: run --workers 2 at least
# 95% of toss --threads 2 at 10^6 paper tosses)? Times `dicesim toss --threads W` and
# `dicesim run --workers W` on the same scene, seed and N, alternating, R rounds: wall clock of
# the whole command and CPU time (user + sys, children included). Prints each round's ratio
# toss_wall / run_wall (1.0: as fast), the median, and the load average. On a shared machine the
# wall ratio is only meaningful when it is otherwise idle; the CPU columns show the work each path
# does, and a run at N = 1000 shows the fixed cost (start-up, hand-shake, end) alone.
# `run` opens LCM: the script re-runs itself in a private network namespace (root).
# Usage: bench/run_vs_toss.sh [DICESIM] [N] [W] [R] [SCENE]
set -euo pipefail
. "$(dirname "$0")/private_net.sh" "$@"
DICESIM=${1:-build/apps/dicesim}
N=${2:-1000000}
W=${3:-2}
R=${4:-3}
SCENE=${5:-scenes/paper/die1.toml}

out=$(mktemp); trap 'rm -f "$out"' EXIT
measure() {  # prints "wall cpu"
  /usr/bin/time -f '%e %U %S' -o "$out" "$@" > /dev/null 2>&1
  awk '{printf "%s %.2f\n", $1, $2 + $3}' "$out"
}
ratios=()
for ((r = 1; r <= R; r++)); do
  read -r tw tc < <(measure "$DICESIM" toss "$SCENE" -n "$N" -j "$W" --json)
  read -r rw rc < <(measure "$DICESIM" run "$SCENE" -n "$N" --workers "$W" --json)
  ratio=$(awk -v a="$tw" -v b="$rw" 'BEGIN {printf "%.3f", a / b}')
  ratios+=("$ratio")
  printf 'round %d: toss %s s wall (%s s cpu), run %s s wall (%s s cpu), ratio %s  load %s\n' \
    "$r" "$tw" "$tc" "$rw" "$rc" "$ratio" "$(cut -d' ' -f1-3 /proc/loadavg)"
done
median=$(printf '%s\n' "${ratios[@]}" | sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}')
printf 'N %s, W %s: median ratio toss/run %s over %d rounds; load %s\n' "$N" "$W" "$median" "$R" "$(cut -d' ' -f1-3 /proc/loadavg)"
