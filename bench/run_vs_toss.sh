#!/bin/bash
# bench/run_vs_toss.sh [DICESIM] [SCENE] [FIDELITY] [N] [REPS] — what distribution costs (root: it
# makes a private network namespace). Times `dicesim toss --threads 2` and `dicesim run --workers 2`
# on the same scene, fidelity, seed and N, alternately, REPS times each (default 3), and prints the
# best wall time of each, their ratio (target: run >= 90% of toss's throughput), whether the counts
# are identical, and the run's messages per toss (from the aggregator's health line: in + out).
# Defaults: build/apps/dicesim, scenes/dice/d20.toml, paper, 10^6, 3. Not CI: minutes at full size.
set -euo pipefail
. "$(dirname "$0")/private_net.sh" "$@"

bin=${1:-build/apps/dicesim} scene=${2:-scenes/dice/d20.toml} fidelity=${3:-paper} n=${4:-1000000} reps=${5:-3}
work=$(mktemp -d /tmp/dicesim-rvt-XXXXXX)
trap 'rm -rf "$work"' EXIT
stable() { sed -E 's/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//; s/"tosses_per_s":[^,}]*,?//' "$1"; }
now() { date +%s.%N; }

best_toss=999999 best_run=999999
calc() { awk "BEGIN { print $* }"; }
for r in $(seq "$reps"); do
  t0=$(now)
  "$bin" toss "$scene" --fidelity "$fidelity" -n "$n" --seed 1 --threads 2 --json > "$work/toss.json" 2> /dev/null
  t1=$(now)
  "$bin" run "$scene" --fidelity "$fidelity" -n "$n" --seed 1 --workers 2 --json > "$work/run.json" 2> "$work/run.err"
  t2=$(now)
  tt=$(calc "$t1 - $t0") tr=$(calc "$t2 - $t1")
  echo "rep $r: toss --threads 2 ${tt} s, run --workers 2 ${tr} s"
  best_toss=$(calc "($tt < $best_toss) ? $tt : $best_toss")
  best_run=$(calc "($tr < $best_run) ? $tr : $best_run")
done
same=no
[ "$(stable "$work/toss.json")" = "$(stable "$work/run.json")" ] && same=yes
msgs_in=$(grep -oE "messages in [0-9]+" "$work/run.err" | tail -n1 | grep -oE '[0-9]+$')
msgs_out=$(grep -oE "out [0-9]+, unauth" "$work/run.err" | tail -n1 | grep -oE '[0-9]+')
faces=$(jq '.faces | length' "$work/run.json")
printf 'scene %s (%s outcomes), %s, %s tosses: best toss %.2f s, best run %.2f s, run/toss throughput %.1f%%; counts identical: %s\n' \
  "$scene" "$faces" "$fidelity" "$n" "$best_toss" "$best_run" "$(calc "100 * $best_toss / $best_run")" "$same"
printf 'messages (last run): in %s, out %s; per 1000 tosses: %.3f\n' "$msgs_in" "$msgs_out" \
  "$(calc "1000 * ($msgs_in + $msgs_out) / $n")"
echo "load: $(uptime)"
