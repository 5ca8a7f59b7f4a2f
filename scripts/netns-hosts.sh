#!/usr/bin/env bash
# Builds "hosts" on this machine for multi-host tests of `sensornet launch --hosts`: network
# namespaces joined by veth pairs to a bridge, and removes them again.
#
#   scripts/netns-hosts.sh up NAME SUBNET COUNT   # e.g. up snt1 10.231.7 3
#   scripts/netns-hosts.sh down NAME
#
# up makes, for i = 1..COUNT:
#   namespace NAME-hI, with lo up and eth0 = SUBNET.I/24 (no default route);
#   veth pair: eth0 inside the namespace, NAME-vI outside, enslaved to the bridge;
# and the bridge NAME-br in the root namespace with address SUBNET.254/24, so that a launcher
# started in the root namespace reaches every host. Nothing is connected to a physical
# interface and no namespace has a route beyond SUBNET.0/24: the traffic stays on the veths,
# the bridge and each namespace's lo. It prints one line per host: "NAME-hI SUBNET.I NAME-vI".
# It refuses a NAME already in use or a SUBNET already on an interface (tests running in
# parallel pick their own), and removes what it made if any step fails.
#
# Where Docker runs (or anything else that sets the FORWARD policy to DROP and loads
# br_netfilter, so that bridged frames pass iptables' FORWARD chain), up also inserts one rule,
# `-i NAME-br -o NAME-br -j ACCEPT`, tagged with the comment "sensornet-netns NAME", so that the
# namespaces reach each other across the bridge; down removes every rule with that tag. Without
# iptables on the machine there is nothing to allow and nothing is added.
#
# down stops what still runs in NAME's namespaces (SIGKILL to the pids `ip netns pids` lists:
# only processes started inside them), then deletes the namespaces, the veths and the bridge.
# It succeeds when there is nothing to remove, so it can run in any cleanup path.
#
# NAME: 1 to 8 lowercase letters or digits (interface names are at most 15 characters).
# SUBNET: the first three numbers of a /24, such as 10.231.7. Needs root (CAP_NET_ADMIN) and
# iproute2.
set -euo pipefail

usage() {
  echo "usage: $0 up NAME SUBNET COUNT | down NAME" >&2
  exit 2
}

check_name() {
  [[ "$1" =~ ^[a-z0-9]{1,8}$ ]] || { echo "$0: NAME: expected 1 to 8 lowercase letters or digits, got '$1'" >&2; exit 2; }
}

# The FORWARD rule that lets frames cross NAME's bridge, and only it (see above).
forward_rule() { echo "FORWARD -i $1-br -o $1-br -m comment --comment sensornet-netns-$1 -j ACCEPT"; }

allow_forwarding() {
  command -v iptables >/dev/null || return 0
  # shellcheck disable=SC2046
  iptables -I $(forward_rule "$1")
}

remove_forwarding() {
  command -v iptables >/dev/null || return 0
  # shellcheck disable=SC2046
  while iptables -D $(forward_rule "$1") 2>/dev/null; do :; done
}

down() {
  local name=$1 ns pid
  remove_forwarding "$name"
  for ns in $(ip netns list | awk '{print $1}' | grep -E "^${name}-h[0-9]+$" || true); do
    for pid in $(ip netns pids "$ns" 2>/dev/null || true); do
      kill -KILL "$pid" 2>/dev/null || true
    done
    ip netns delete "$ns" 2>/dev/null || true
  done
  for link in $(ip -o link show | awk -F': ' '{print $2}' | cut -d@ -f1 | grep -E "^${name}-(v[0-9]+|br)$" || true); do
    ip link delete "$link" 2>/dev/null || true
  done
}

up() {
  local name=$1 subnet=$2 count=$3 i ns
  [[ "$subnet" =~ ^([0-9]{1,3})\.([0-9]{1,3})\.([0-9]{1,3})$ ]] || { echo "$0: SUBNET: expected three numbers such as 10.231.7, got '$subnet'" >&2; exit 2; }
  for part in "${BASH_REMATCH[@]:1}"; do
    (( part <= 255 )) || { echo "$0: SUBNET: expected numbers up to 255, got '$subnet'" >&2; exit 2; }
  done
  [[ "$count" =~ ^[0-9]+$ ]] && (( count >= 1 && count <= 200 )) || { echo "$0: COUNT: expected 1 to 200, got '$count'" >&2; exit 2; }
  if ip netns list | awk '{print $1}' | grep -qE "^${name}-h[0-9]+$" || ip link show "${name}-br" >/dev/null 2>&1; then
    echo "$0: NAME $name is in use (namespaces or bridge exist)" >&2
    exit 3
  fi
  if ip -4 -o addr show | grep -qF " ${subnet}."; then
    echo "$0: SUBNET $subnet.0/24 is already on an interface" >&2
    exit 3
  fi
  trap 'status=$?; down "$name"; exit $status' ERR INT TERM
  ip link add "${name}-br" type bridge
  ip addr add "${subnet}.254/24" dev "${name}-br"
  ip link set "${name}-br" up
  allow_forwarding "$name"
  for (( i = 1; i <= count; i++ )); do
    ns="${name}-h${i}"
    ip netns add "$ns"
    ip -n "$ns" link set lo up
    ip link add "${name}-v${i}" type veth peer name "${name}-p${i}"
    ip link set "${name}-p${i}" netns "$ns"
    ip -n "$ns" link set "${name}-p${i}" name eth0
    ip -n "$ns" addr add "${subnet}.${i}/24" dev eth0
    ip -n "$ns" link set eth0 up
    ip link set "${name}-v${i}" master "${name}-br"
    ip link set "${name}-v${i}" up
  done
  trap - ERR INT TERM
  for (( i = 1; i <= count; i++ )); do
    echo "${name}-h${i} ${subnet}.${i} ${name}-v${i}"
  done
}

[[ $# -ge 2 ]] || usage
case "$1" in
  up)
    [[ $# -eq 4 ]] || usage
    check_name "$2"
    up "$2" "$3" "$4"
    ;;
  down)
    [[ $# -eq 2 ]] || usage
    check_name "$2"
    down "$2"
    ;;
  *) usage ;;
esac
