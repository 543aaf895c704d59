#!/usr/bin/env bash
# examples/slurm/ on a real one-node Slurm cluster that this script starts for itself: munged,
# slurmctld and slurmd (Debian's munge and slurm-wlm) on loopback inside a private network
# namespace, with a generated slurm.conf, all state in a temporary folder. Run by CTest:
#   slurm_cluster.sh DICESIM_BINARY SHARDS TOSSES [fit]
# The example's job array of SHARDS shards and its merge step (afterok dependency) must give the
# counts of one `dicesim toss` of all TOSSES paper tosses. With `fit`: examples/slurm/fit-submit.sh,
# a fit (TOSSES per point) sharded by point in passes of SHARDS-task arrays, whose merge must print
# exactly the unsharded `dicesim fit --json` but for elapsed_s and threads. Under CI=true, not
# being able to run fails.
set -euo pipefail
[ -n "${DICESIM_TRACE:-}" ] && set -x

net_multicast=off  # private_net.sh: lo without multicast (Slurm needs none)
. "$(dirname "$0")/private_net.sh" slurm "$@"
bin=$(readlink -f "$1") shards=$2 tosses=$3 mode=${4:-toss}
for p in munged mungekey slurmctld slurmd sbatch squeue; do
  command -v "$p" > /dev/null || skip "no $p (Debian packages slurm-wlm and munge)"
done
# Slurm binds its ports through getaddrinfo(AI_ADDRCONFIG), which finds no address family when the
# only interface is loopback: a veth pair with both ends in this namespace (nothing can leave) gives it one.
ip link add dicesim0 type veth peer name dicesim1
ip addr add 10.255.255.1/32 dev dicesim0
ip link set dicesim0 up
ip link set dicesim1 up

chmod 755 "$work"
cleanup() {  # slurmctld, slurmd and munged get a TERM first; DICESIM_KEEP keeps the work folder
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  sleep 1
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  [ -n "${DICESIM_KEEP:-}" ] || rm -rf "$work"
}
fail() { echo "FAIL [slurm]: $*" >&2; for f in "$work"/*.log "$work"/parts/*.log; do [ -f "$f" ] && { echo "--- $f" >&2; tail -n 15 "$f" >&2; }; done; exit 1; }

# munge: a fresh key, a socket of its own.
mkdir -m 700 "$work/munge"
mungekey -c -k "$work/munge/munge.key" 2> /dev/null || dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 2> /dev/null
chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/munge.sock" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/munge.log" --seed-file="$work/munge/seed" ||
  fail "munged did not start"
pids+=("$(cat "$work/munge/munged.pid")")

host=$(hostname -s)
cpus=$(nproc)
mkdir -p "$work/state" "$work/spool" "$work/parts"
cat > "$work/slurm.conf" <<CONF
ClusterName=dicesim-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=6817
SlurmdPort=6818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$work/munge/munge.sock
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
MaxArraySize=1001
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$work/slurm.conf
slurmctld -i -D > "$work/slurmctld.out.log" 2>&1 & pids+=($!)
slurmd -D -N "$host" > "$work/slurmd.out.log" 2>&1 & pids+=($!)
for ((t = 0; t < 300; t++)); do
  sinfo -h -o '%T' 2> /dev/null | grep -qE '^idle' && break
  sleep 0.2
done
sinfo -h -o '%T' | grep -qE '^idle' || fail "the node did not come up idle within 60 s: $(sinfo 2>&1)"

wait_queue() {
  for ((t = 0; t < 3000; t++)); do
    [ -z "$(squeue -h 2> /dev/null)" ] && break
    sleep 0.2
  done
  [ -z "$(squeue -h)" ] || fail "jobs still queued after 600 s: $(squeue)"
}

if [ "$mode" = fit ]; then
  # Counts that put the estimate inside the range: later rounds' points depend on earlier ones.
  printf 'face,count\n1,150\n2,170\n3,168\n4,166\n5,170\n6,176\n' > "$work/counts.csv"
  fit_args="$src_dir/scenes/paper/die1.toml --data $work/counts.csv --data $work/counts.csv --scene $src_dir/scenes/paper/die2.toml"
  fit_args+=" --param materials.steel.density=3000:20000 --fidelity static -n $tosses --seed 3"
  # shellcheck disable=SC2086
  "$bin" fit $fit_args -j 2 --json > "$work/ref-fit.json" 2> /dev/null
  cd "$work/parts"
  merge_job=$(FIT_ARGS="$fit_args" DICESIM="$bin" "$src_dir/examples/slurm/fit-submit.sh" "$shards" "$work/parts/fit")
  echo "fit merge job $merge_job; waiting"
  wait_queue
  [ -s "$work/parts/fit/fit.json" ] || fail "the fit merge step wrote no fit.json ($(cat "$work/parts"/dicesim-fit-merge-*.log 2>&1))"
  fstable() { jq -cS 'del(.elapsed_s, .provenance.threads)' "$1"; }
  if [ "$(fstable "$work/ref-fit.json")" != "$(fstable "$work/parts/fit/fit.json")" ]; then
    echo "fit:   $(fstable "$work/ref-fit.json")" >&2
    echo "slurm: $(fstable "$work/parts/fit/fit.json")" >&2
    fail "the Slurm-sharded fit differs from dicesim fit"
  fi
  echo "PASS [slurm fit]: $(ls "$work/parts/fit"/fit-part-*.json | wc -l) parts of $shards-task passes merged to dicesim fit's JSON"
  exit 0
fi

# The reference, then the example exactly as a user submits it.
"$bin" toss scenes/paper/die1.toml --tosses "$tosses" --seed 1 --threads 2 --json > "$work/ref.json"
cd "$work/parts"
merge_job=$(DICESIM="$bin" "$src_dir/examples/slurm/submit.sh" "$src_dir/scenes/paper/die1.toml" "$tosses" "$shards" "$work/parts")
echo "merge job $merge_job; waiting"
wait_queue
[ "$(ls "$work/parts"/part-*.json | wc -l)" -eq "$shards" ] || fail "expected $shards part files: $(ls "$work/parts")"
[ -s "$work/parts/run.json" ] || fail "the merge step wrote no run.json ($(cat "$work/parts"/dicesim-merge-*.log 2>&1))"
stable() { sed -E 's/"scene":"[^"]*",?//g; s/"elapsed_s":[^,}]*,?//; s/"threads":[0-9]+,?//g; s/"tosses_per_s":[^,}]*,?//; s/"seconds":[^,}]*,?//g' "$1"; }  # threads: also provenance's
if [ "$(stable "$work/ref.json")" != "$(stable "$work/parts/run.json")" ]; then
  echo "toss:  $(stable "$work/ref.json")" >&2
  echo "slurm: $(stable "$work/parts/run.json")" >&2
  fail "the merged Slurm array differs from dicesim toss"
fi
echo "PASS [slurm]: $shards shards of $tosses tosses merged to toss's counts"
