# Sourced by the integration scripts as their first act: `. private_net.sh PREFIX "$@"` from the
# top of SCRIPT. Re-runs SCRIPT inside a private network namespace (only loopback, multicast on,
# a 224/4 route), so nothing it sends can leave; exits 77 (CTest skip) when not root. Then sets
# src_dir (and cds there), work (a temporary folder), pids (killed at exit) and the LCM URL.
if [ "${DICESIM_NETNS:-}" != "1" ]; then
  if [ "$(id -u)" -ne 0 ]; then echo "SKIP: network namespaces need root"; exit 77; fi
  exec unshare --net env DICESIM_NETNS=1 "$0" "${@:2}"
fi
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
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
