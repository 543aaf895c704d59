# Sourced by the integration scripts as their first act: `. private_net.sh PREFIX "$@"` from the
# top of SCRIPT. Re-runs SCRIPT inside a private network namespace (only loopback, multicast on,
# a 224/4 route; with net_multicast=off set before, multicast off and no such route), so nothing it
# sends can leave; exits 77 (CTest skip) when not root, or 1 when $CI is set (in CI a test that
# cannot run fails). Then sets src_dir (and cds there), work (a temporary folder), pids (killed at
# exit by cleanup, which a script may redefine) and the LCM URL.
skip() {  # skip REASON: a CTest skip, except under CI
  if [ -n "${CI:-}" ]; then echo "FAIL: cannot run under CI=$CI: $1" >&2; exit 1; fi
  echo "SKIP: $1"; exit 77
}
if [ "${DICESIM_NETNS:-}" != "1" ]; then
  if [ "$(id -u)" -ne 0 ]; then skip "network namespaces need root"; fi
  unshare --net true 2> /dev/null || skip "cannot make a network namespace here (unshare --net failed: a container without CAP_SYS_ADMIN?)"
  exec unshare --net env DICESIM_NETNS=1 "$0" "${@:2}"
fi
ip link set lo up
if [ "${net_multicast:-on}" = on ]; then
  ip link set lo multicast on
  ip route add 224.0.0.0/4 dev lo
else
  ip link set lo multicast off
fi
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=0"

src_dir=$(cd "$(dirname "$0")/../.." && pwd)
cd "$src_dir"
work=$(mktemp -d "/tmp/dicesim-$1-XXXXXX")
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
