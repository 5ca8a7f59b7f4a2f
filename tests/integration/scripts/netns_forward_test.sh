#!/usr/bin/env bash
# scripts/netns-hosts.sh on a machine where Docker runs: the FORWARD policy is DROP and bridged
# frames pass iptables (br_netfilter). The harness's hosts must still reach each other across
# their bridge, and `down` must leave no rule behind. Docker's state is made, not assumed: inside
# a private network namespace of this test (iptables and the bridge sysctl are per namespace), so
# the machine's own firewall is never touched. Exit 77 (skipped) without root, iproute2, iptables
# or br_netfilter; 0 when the hosts talk and the rule is gone; 1 otherwise.
set -euo pipefail
harness=$1
[[ "$(id -u)" -eq 0 ]] || { echo "skip: not root"; exit 77; }
command -v ip >/dev/null || { echo "skip: no iproute2"; exit 77; }
command -v iptables >/dev/null || { echo "skip: no iptables (nothing can drop bridged frames)"; exit 77; }
[[ -e /proc/sys/net/bridge/bridge-nf-call-iptables ]] || modprobe br_netfilter 2>/dev/null || true
[[ -e /proc/sys/net/bridge/bridge-nf-call-iptables ]] || { echo "skip: no br_netfilter"; exit 77; }

outer="snfwd$$"
name="f$(( $$ % 100000 ))"
subnet="10.239.$(( $$ % 250 ))"
cleanup() {
  nsenter --net="/run/netns/$outer" "$harness" down "$name" >/dev/null 2>&1 || true
  ip netns delete "$outer" 2>/dev/null || true
}
trap cleanup EXIT
ip netns add "$outer"
# nsenter, not `ip netns exec`: the hosts the harness adds must outlive its mount namespace.
in_outer() { nsenter --net="/run/netns/$outer" "$@"; }
in_outer ip link set lo up
in_outer iptables -P FORWARD DROP  # what dockerd does
in_outer sysctl -qw net.bridge.bridge-nf-call-iptables=1

# One UDP datagram from host 1 to host 2 across the bridge: prints "got" or "nothing". The
# datagram goes once the listener is bound (a loaded machine may take seconds to start python).
send_across() {
  local bound
  bound=$(mktemp -u /tmp/snfwd-bound.XXXXXX)
  in_outer ip netns exec "$name-h2" timeout 20 python3 -c "
import socket
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(('$subnet.2', 7399)); s.settimeout(3)
open('$bound', 'w').close()
try:
    s.recv(16); print('got')
except OSError:
    print('nothing')" &
  local listener=$! _
  for _ in $(seq 1 150); do [[ -e "$bound" ]] && break; sleep 0.1; done
  rm -f "$bound"
  in_outer ip netns exec "$name-h1" python3 -c "
import socket
socket.socket(socket.AF_INET, socket.SOCK_DGRAM).sendto(b'x', ('$subnet.2', 7399))"
  wait "$listener"
}

in_outer "$harness" up "$name" "$subnet" 2 >/dev/null
result=$(send_across)
[[ "$result" == got ]] || { echo "FAIL: host 1 did not reach host 2 across a dropping FORWARD chain"; exit 1; }
# The rule is what made the difference: without it the same datagram is dropped.
in_outer iptables -D FORWARD -i "$name-br" -o "$name-br" -m comment --comment "sensornet-netns-$name" -j ACCEPT
result=$(send_across)
[[ "$result" == nothing ]] || { echo "FAIL: the datagram crossed without the rule (the test proves nothing)"; exit 1; }
in_outer iptables -I FORWARD -i "$name-br" -o "$name-br" -m comment --comment "sensornet-netns-$name" -j ACCEPT
in_outer "$harness" down "$name"
if in_outer iptables -S FORWARD | grep -q "sensornet-netns-$name"; then
  echo "FAIL: down left the FORWARD rule behind"; exit 1
fi
echo "ok: the hosts talk across a dropping FORWARD chain; down removed the rule"
