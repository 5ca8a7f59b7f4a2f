#!/usr/bin/env bash
# The fresh-machine check: scripts/demo.sh inside a bare Debian 12 container, so that a package
# scripts/install-deps.sh forgets fails here instead of in a user's first hour. This machine's
# image holds packages a bare Debian 12 lacks; only a bare container shows a missing step.
#
#   scripts/test-fresh-debian.sh [extra `sensornet launch` flags for the demo]
#
# What it does, and undoes at the end (also on failure or Ctrl-C):
#   - installs docker.io and debootstrap when missing (they stay installed);
#   - starts dockerd when none answers, and stops it again;
#   - uses a local `debian:12` image when there is one, otherwise builds a bare one with
#     `debootstrap --variant=minbase bookworm` from this machine's Debian mirror (no registry is
#     needed) and removes it afterwards;
#   - copies the files git tracks (what a clean clone holds) into a container and runs
#     scripts/demo.sh there as root; then, in the same container, the README's "Many hosts"
#     recipe (docs/guide/many-hosts.md, "Tested on one machine": three network-namespace hosts,
#     so the container gets NET_ADMIN and SYS_ADMIN).
# Exit status: 0 when both runs completed, else the first failure's (1 when the check itself
# could not run).
# Needs root: it starts dockerd and installs packages.
set -euo pipefail
cd "$(dirname "$0")/.."

docker_host_log_prefix=test-fresh-debian
source scripts/docker-host.sh
die() { docker_host_log "$*"; exit 1; }

work=$(mktemp -d /tmp/sensornet-fresh.XXXXXX)
container="sensornet-fresh-$$"
cleanup() {
  local status=$?
  docker rm -f "$container" >/dev/null 2>&1 || true
  docker_host_down
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

docker_host_up "$work" docker.io debootstrap || die "no Docker Engine to run the check in"
docker_base_image "$work" || die "no Debian 12 base image"
image=$docker_host_image

# The tracked files only: what a clean clone holds (with this tree's uncommitted edits).
git ls-files -z | tar --null -T - -cf "$work/tree.tar"

docker_host_log "running scripts/demo.sh in a bare Debian 12 container ($image)"
started=$SECONDS
docker create --name "$container" --cap-add NET_ADMIN --cap-add SYS_ADMIN \
  --security-opt apparmor=unconfined "$image" \
  bash -c 'set -euo pipefail
    mkdir -p /sensornet && tar -xf /tree.tar -C /sensornet && cd /sensornet
    scripts/demo.sh "$@"
    echo "test-fresh-debian: the demo completed; now the README recipe \"Many hosts\"" >&2
    for tool in ip pgrep ps openssl; do
      command -v "$tool" >/dev/null || { echo "test-fresh-debian: no $tool after install-deps" >&2; exit 1; }
    done
    scripts/netns-hosts.sh up sn 10.78.0 3
    trap "scripts/netns-hosts.sh down sn" EXIT
    build/launcher/sensornet launch scenarios/default.yaml --hosts config/hosts-netns.yaml \
      --episodes 4 --time-scale 10' fresh "$@" >/dev/null
docker cp "$work/tree.tar" "$container:/tree.tar"
status=0
docker start -a "$container" || status=$?
docker_host_log "container finished with status $status after $((SECONDS - started)) s"
exit "$status"
