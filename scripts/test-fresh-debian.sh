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
#     recipe (three network-namespace hosts, so the container gets NET_ADMIN and SYS_ADMIN).
# Exit status: 0 when both runs completed, else the first failure's (1 when the check itself
# could not run).
# Needs root: it starts dockerd and installs packages.
set -euo pipefail
cd "$(dirname "$0")/.."

log() { echo "test-fresh-debian: $*" >&2; }
die() { log "$*"; exit 1; }

[[ "$(id -u)" -eq 0 ]] || die "needs root (it starts dockerd and installs packages)"

missing=()
command -v dockerd >/dev/null || missing+=(docker.io)
command -v debootstrap >/dev/null || missing+=(debootstrap)
if ((${#missing[@]} > 0)); then
  log "installing ${missing[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" \
    >/dev/null
fi

work=$(mktemp -d /tmp/sensornet-fresh.XXXXXX)
dockerd_pid=""
made_image=""
container="sensornet-fresh-$$"
cleanup() {
  local status=$?
  docker rm -f "$container" >/dev/null 2>&1 || true
  if [[ -n "$made_image" ]]; then docker rmi -f "$made_image" >/dev/null 2>&1 || true; fi
  if [[ -n "$dockerd_pid" ]]; then
    kill "$dockerd_pid" 2>/dev/null || true
    for _ in $(seq 1 100); do kill -0 "$dockerd_pid" 2>/dev/null || break; sleep 0.1; done
  fi
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

if ! docker info >/dev/null 2>&1; then
  log "starting dockerd (log: $work/dockerd.log)"
  dockerd >"$work/dockerd.log" 2>&1 &
  dockerd_pid=$!
  for _ in $(seq 1 300); do docker info >/dev/null 2>&1 && break; sleep 0.1; done
  docker info >/dev/null 2>&1 || { tail -n 20 "$work/dockerd.log" >&2; die "dockerd did not answer within 30 s"; }
fi

# This machine's Debian mirror: the first URI of its apt sources (deb822 or one-line form).
mirror() {
  local uri
  uri=$(grep -hE '^URIs:' /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '{print $2}' \
    | grep -v security | head -n 1 || true)
  [[ -n "$uri" ]] || uri=$(grep -hE '^deb ' /etc/apt/sources.list 2>/dev/null | awk '{print $2}' \
    | grep -v security | head -n 1 || true)
  echo "${uri:-http://deb.debian.org/debian}"
}

image=debian:12
if ! docker image inspect "$image" >/dev/null 2>&1; then
  image="sensornet-fresh/debian:12-$$"
  log "no local debian:12: making a bare one with debootstrap from $(mirror)"
  started=$SECONDS
  debootstrap --variant=minbase bookworm "$work/root" "$(mirror)" >"$work/debootstrap.log" 2>&1 \
    || { tail -n 20 "$work/debootstrap.log" >&2; die "debootstrap failed"; }
  tar -C "$work/root" -c . | docker import - "$image" >/dev/null
  made_image=$image
  rm -rf "$work/root"
  log "base image $image made in $((SECONDS - started)) s"
fi

# The tracked files only: what a clean clone holds (with this tree's uncommitted edits).
git ls-files -z | tar --null -T - -cf "$work/tree.tar"

log "running scripts/demo.sh in a bare Debian 12 container ($image)"
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
log "container finished with status $status after $((SECONDS - started)) s"
exit "$status"
