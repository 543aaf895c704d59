# Sourced first by the bench scripts that open LCM or DDS: `. "$(dirname "$0")/private_net.sh" "$@"`.
# Re-runs the script inside a private network namespace (only loopback up, multicast on, a 224/4
# route), so nothing it sends can leave this host; exits 77 when not root. (The integration tests'
# tests/integration/private_net.sh does the same plus their work folder and cleanup.)
if [ "${DICESIM_NETNS:-}" != "1" ]; then
  if [ "$(id -u)" -ne 0 ]; then echo "$(basename "$0"): needs root (unshare --net)" >&2; exit 77; fi
  exec unshare --net env DICESIM_NETNS=1 "$0" "$@"
fi
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
