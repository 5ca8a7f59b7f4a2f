#!/bin/sh
# sensornet-await-peers NAME... -- PROGRAM ARGS...: waits until every NAME resolves (DNS, as
# Docker's embedded server answers for the services of a swarm stack), then runs PROGRAM with
# every address of every NAME as a unicast peer of its own.
# Cyclone DDS resolves its unicast peers once, at start: a service whose task is not up yet would
# be skipped, and two services started at the same moment might never meet. On a swarm, where
# `depends_on` does not order the start, every service waits for the peers it must reach.
# Cyclone also takes one address per name, and a replicated service's name (endpoint_mode dnsrr)
# has one per task: a restarted coordinator or fusion center, at a new address the others
# resolved before it existed, would find only one of the sensor tasks. So the addresses of the
# NAMEs are added to SENSORNET_CYCLONE_CONFIG as peers (a configuration fragment after it).
# Gives up (exit 1) after SENSORNET_AWAIT_PEERS_S seconds (default 120).
set -eu
limit=${SENSORNET_AWAIT_PEERS_S:-120}
names=""
while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do names="$names $1"; shift; done
[ "$#" -gt 1 ] || { echo "usage: sensornet-await-peers NAME... -- PROGRAM ARGS..." >&2; exit 2; }
shift
start=$(date +%s)
peers=""
for name in $names; do
  until getent hosts "$name" >/dev/null; do
    if [ $(( $(date +%s) - start )) -ge "$limit" ]; then
      echo "sensornet-await-peers: $name did not resolve within $limit s" >&2
      exit 1
    fi
    sleep 0.2
  done
  for address in $(getent ahostsv4 "$name" | awk '{ print $1 }' | sort -u); do
    peers="$peers<Peer Address=\"$address\"/>"
  done
done
if [ -n "${SENSORNET_CYCLONE_CONFIG:-}" ] && [ -n "$peers" ]; then
  SENSORNET_CYCLONE_CONFIG="$SENSORNET_CYCLONE_CONFIG,<CycloneDDS><Domain Id=\"any\"><Discovery><Peers>$peers</Peers></Discovery></Domain></CycloneDDS>"
  export SENSORNET_CYCLONE_CONFIG
fi
exec "$@"
