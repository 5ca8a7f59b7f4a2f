# A Docker Engine on this machine for the container checks (scripts/test-fresh-debian.sh,
# scripts/test-containers.sh), set up and taken down again. Sourced, not run:
#
#   source scripts/docker-host.sh
#   docker_host_up "$work" docker.io debootstrap   # root; installs what is missing; dockerd
#   trap 'docker_host_down' EXIT                    # stops the dockerd it started, removes the
#   docker_base_image "$work"                       #   base image it made
#   docker create ... "$docker_host_image" ...
#
# - docker_host_up WORK PACKAGES...: installs the Debian packages that are missing (they stay
#   installed) and starts dockerd when none answers (its log in WORK/dockerd.log);
# - docker_base_image WORK: sets docker_host_image to `debian:12` when the Engine has it,
#   otherwise builds a bare Debian 12 with `debootstrap --variant=minbase bookworm` from this
#   machine's Debian mirror (no registry is needed), imports it and names that;
# - docker_host_down: removes the base image it made and stops the dockerd it started.
# Messages go to stderr, prefixed with $docker_host_log_prefix.

docker_host_log_prefix=${docker_host_log_prefix:-docker-host}
docker_host_dockerd_pid=""
docker_host_made_image=""
docker_host_image=""

docker_host_log() { echo "$docker_host_log_prefix: $*" >&2; }

docker_host_up() {
  local work=$1
  shift
  [[ "$(id -u)" -eq 0 ]] || { docker_host_log "needs root (it starts dockerd and installs packages)"; return 1; }
  local missing=() package
  for package in "$@"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" \
      || missing+=("$package")
  done
  if ((${#missing[@]} > 0)); then
    docker_host_log "installing ${missing[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" \
      >/dev/null
  fi
  if ! docker info >/dev/null 2>&1; then
    docker_host_log "starting dockerd (log: $work/dockerd.log)"
    dockerd >"$work/dockerd.log" 2>&1 &
    docker_host_dockerd_pid=$!
    local _
    for _ in $(seq 1 300); do docker info >/dev/null 2>&1 && break; sleep 0.1; done
    if ! docker info >/dev/null 2>&1; then
      tail -n 20 "$work/dockerd.log" >&2
      docker_host_log "dockerd did not answer within 30 s"
      return 1
    fi
  fi
}

# This machine's Debian mirror: the first URI of its apt sources (deb822 or one-line form).
docker_host_mirror() {
  local uri
  uri=$(grep -hE '^URIs:' /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '{print $2}' \
    | grep -v security | head -n 1 || true)
  [[ -n "$uri" ]] || uri=$(grep -hE '^deb ' /etc/apt/sources.list 2>/dev/null | awk '{print $2}' \
    | grep -v security | head -n 1 || true)
  echo "${uri:-http://deb.debian.org/debian}"
}

docker_base_image() {
  local work=$1
  docker_host_image=debian:12
  docker image inspect debian:12 >/dev/null 2>&1 && return
  local image="sensornet-base/debian:12-$$" started=$SECONDS
  docker_host_log "no local debian:12: making a bare one with debootstrap from $(docker_host_mirror)"
  if ! debootstrap --variant=minbase bookworm "$work/root" "$(docker_host_mirror)" \
    >"$work/debootstrap.log" 2>&1; then
    tail -n 20 "$work/debootstrap.log" >&2
    docker_host_log "debootstrap failed"
    return 1
  fi
  tar -C "$work/root" -c . | docker import - "$image" >/dev/null
  docker_host_made_image=$image
  docker_host_image=$image
  rm -rf "$work/root"
  docker_host_log "base image $image made in $((SECONDS - started)) s"
}

docker_host_down() {
  if [[ -n "$docker_host_made_image" ]]; then
    docker rmi -f "$docker_host_made_image" >/dev/null 2>&1 || true
  fi
  if [[ -n "$docker_host_dockerd_pid" ]]; then
    kill "$docker_host_dockerd_pid" 2>/dev/null || true
    local _
    for _ in $(seq 1 100); do kill -0 "$docker_host_dockerd_pid" 2>/dev/null || break; sleep 0.1; done
  fi
}
