#!/bin/bash
# bench/run_vs_toss.sh [DICESIM] [SCENE] [FIDELITY] [N] [REPS] — what distribution costs (root: it
# makes a private network namespace). Times `dicesim toss --threads 2` and `dicesim run --workers 2`
# on the same scene, fidelity, seed and N, alternately, REPS times each (default 3): wall clock and
# CPU time (user + sys, children included) of each whole command. Prints each round, the best wall
# time of each and their ratio, the median of the rounds' own ratios (each round's pair ran back to
# back, so load that comes and goes hits both alike) (targets: run >= 90% of toss's throughput on a d20, issue 12; >= 95%
# at 10^6 paper tosses, issue 14), the CPU ratio (the work each path does; on a loaded machine the
# wall ratio says more about the scheduler than about dicesim), whether the counts are identical,
# and the run's messages per 1000 tosses (from the aggregator's health line: in + out) and tail
# splits (leases halved for an idle worker at the end).
# N = 1000 shows `run`'s fixed cost (start-up, hand-shake, end) alone.
# Defaults: build/apps/dicesim, scenes/dice/d20.toml, paper, 10^6, 3. Not CI: minutes at full size.
set -euo pipefail
. "$(dirname "$0")/private_net.sh" "$@"

bin=${1:-build/apps/dicesim} scene=${2:-scenes/dice/d20.toml} fidelity=${3:-paper} n=${4:-1000000} reps=${5:-3}
work=$(mktemp -d /tmp/dicesim-rvt-XXXXXX)
trap 'rm -rf "$work"' EXIT
stable() { sed -E 's/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//; s/"tosses_per_s":[^,}]*,?//' "$1"; }
calc() { awk "BEGIN { print $* }"; }
measure() {  # measure OUT ERR CMD...: prints "wall cpu" (wall to the ms; time's %e has 10 ms steps)
  local out=$1 err=$2 t0 t1; shift 2
  t0=$(date +%s%N)
  /usr/bin/time -f '%U %S' -o "$work/time" "$@" > "$out" 2> "$err"
  t1=$(date +%s%N)
  awk -v w="$(( (t1 - t0) / 1000000 ))" '{printf "%.3f %.2f\n", w / 1000, $1 + $2}' "$work/time"
}

best_toss=999999 best_run=999999 cpu_toss=0 cpu_run=0 ratios=()
for r in $(seq "$reps"); do
  read -r tt tc < <(measure "$work/toss.json" /dev/null \
    "$bin" toss "$scene" --fidelity "$fidelity" -n "$n" --seed 1 --threads 2 --json)
  read -r tr rc < <(measure "$work/run.json" "$work/run.err" \
    "$bin" run "$scene" --fidelity "$fidelity" -n "$n" --seed 1 --workers 2 --json)
  echo "rep $r: toss --threads 2 ${tt} s wall (${tc} s cpu), run --workers 2 ${tr} s wall (${rc} s cpu); load $(cut -d' ' -f1-3 /proc/loadavg)"
  ratios+=("$(calc "100 * $tt / $tr")")
  best_toss=$(calc "($tt < $best_toss) ? $tt : $best_toss")
  best_run=$(calc "($tr < $best_run) ? $tr : $best_run")
  cpu_toss=$(calc "$cpu_toss + $tc") cpu_run=$(calc "$cpu_run + $rc")
done
same=no
[ "$(stable "$work/toss.json")" = "$(stable "$work/run.json")" ] && same=yes
msgs_in=$(grep -oE "messages in [0-9]+" "$work/run.err" | tail -n1 | grep -oE '[0-9]+$')
msgs_out=$(grep -oE "out [0-9]+, unauth" "$work/run.err" | tail -n1 | grep -oE '[0-9]+')
faces=$(jq '.faces | length' "$work/run.json")
median=$(printf '%s\n' "${ratios[@]}" | sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}')
splits=$(grep -oE "tail splits [0-9]+ \([0-9]+" "$work/run.err" | tail -n1 | grep -oE '[0-9]+' | tr '\n' ' ' || true)
printf 'scene %s (%s outcomes), %s, %s tosses: best toss %.3f s, best run %.3f s, run/toss throughput %.1f%% (wall, best), %.1f%% (wall, median of rounds), %.1f%% (cpu); counts identical: %s\n' \
  "$scene" "$faces" "$fidelity" "$n" "$best_toss" "$best_run" "$(calc "100 * $best_toss / $best_run")" "$median" \
  "$(calc "100 * $cpu_toss / $cpu_run")" "$same"
printf 'messages (last run): in %s, out %s; per 1000 tosses: %.3f; tail splits (tosses moved): %s\n' "$msgs_in" "$msgs_out" \
  "$(calc "1000 * ($msgs_in + $msgs_out) / $n")" "${splits:-none}"
echo "load: $(uptime)"
