#!/bin/sh
# sensornet-await-peers NAME... -- PROGRAM ARGS...: waits until every NAME resolves (DNS, as
# Docker's embedded server answers for the services of a swarm stack), then runs PROGRAM.
# Cyclone DDS resolves its unicast peers once, at start: a service whose task is not up yet would
# be skipped, and two services started at the same moment might never meet. On a swarm, where
# `depends_on` does not order the start, every service waits for the peers it must reach.
# Gives up (exit 1) after SENSORNET_AWAIT_PEERS_S seconds (default 120).
set -eu
limit=${SENSORNET_AWAIT_PEERS_S:-120}
names=""
while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do names="$names $1"; shift; done
[ "$#" -gt 1 ] || { echo "usage: sensornet-await-peers NAME... -- PROGRAM ARGS..." >&2; exit 2; }
shift
start=$(date +%s)
for name in $names; do
  until getent hosts "$name" >/dev/null; do
    if [ $(( $(date +%s) - start )) -ge "$limit" ]; then
      echo "sensornet-await-peers: $name did not resolve within $limit s" >&2
      exit 1
    fi
    sleep 0.2
  done
done
exec "$@"
