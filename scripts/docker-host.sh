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
# And what the container tests share:
# - docker_test_options USAGE ARGS...: reads the image options (exit 2 with USAGE on anything
#   else) and sets `test_image` (the image the test runs), `build_image` (true: build it first)
#   and `remove_image` (true: remove it at the end):
#     (none)           build sensornet-test:PID, remove it at the end
#     --keep           build sensornet-test:PID, keep it
#     --tag NAME       build NAME, keep it (for the next test: CI hands it to test-swarm.sh)
#     --image NAME     use NAME, built before, and keep it
#     --image NAME --drop-image   use NAME and remove it at the end;
# - docker_runtime_image WORK TAG [DOCKER BUILD OPTIONS...]: builds docker/Dockerfile as TAG over
#   the base image (the client under nice), noting the images there were before (docker_runtime_image_remove WORK TAG removes TAG
#   and the build's untagged layers again);
# - docker_native_report WORK: runs the containers' run natively once (build/launcher/sensornet,
#   scenarios/default.yaml, 4 episodes, time scale 5, seed 7) into WORK/native.json;
# - docker_costs_match_native WORK REPORT [STATUS]: checks that REPORT has STATUS (completed), all
#   4 episodes complete, fused every measurement it sent and has the native run's realized costs
#   (relative 1e-9: the image is built without -march=native);
# - docker_ready_after LOG DEPLOYED_AT: seconds from DEPLOYED_AT (epoch) to the coordinator's
#   "ready" line in LOG (`docker service logs --timestamps`), or "not logged".
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

docker_test_options() {
  local usage=$1 keep=false given="" tag="" drop=false
  shift
  while (($# > 0)); do
    case "$1" in
      --keep) keep=true ;;
      --image) given=${2:?--image needs a name}; shift ;;
      --tag) tag=${2:?--tag needs a name}; shift ;;
      --drop-image) drop=true ;;
      *) echo "usage: $usage" >&2; exit 2 ;;
    esac
    shift
  done
  if [[ -n "$given" && -n "$tag" ]] || { $drop && [[ -z "$given" ]]; }; then
    echo "usage: $usage (--tag builds, --image uses one built before; --drop-image needs --image)" >&2
    exit 2
  fi
  build_image=true
  remove_image=true
  test_image="sensornet-test:$$"
  if [[ -n "$given" ]]; then
    build_image=false
    test_image=$given
    remove_image=$drop
  elif [[ -n "$tag" ]]; then
    test_image=$tag
    remove_image=false
  elif $keep; then
    remove_image=false
  fi
}

docker_runtime_image() {
  local work=$1 tag=$2
  shift 2
  docker images -aq --no-trunc | sort -u >"$work/images-before"
  docker_host_log "building the image $tag (docker/Dockerfile; log: $work/build.log)"
  local started=$SECONDS
  if ! nice docker build --force-rm "$@" -f docker/Dockerfile --build-arg "BASE_IMAGE=$docker_host_image" \
    -t "$tag" . >"$work/build.log" 2>&1; then
    tail -n 30 "$work/build.log" >&2
    docker_host_log "the image did not build"
    return 1
  fi
  docker_host_log "image built in $((SECONDS - started)) s"
}

docker_runtime_image_remove() {
  local work=$1 tag=$2
  docker rmi -f "$tag" >/dev/null 2>&1 || true
  [[ -f "$work/images-before" ]] || return 0
  docker images -aq --no-trunc | sort -u | comm -13 "$work/images-before" - \
    | xargs -r docker rmi -f >/dev/null 2>&1 || true
}

docker_native_report() {
  local work=$1 attempt _ started ok=false
  [[ -s "$work/native.json" ]] && return 0
  for attempt in 1 2 3; do
    # build/ may be mid-rebuild by someone else: wait until its launcher runs, never build it here.
    for _ in $(seq 1 120); do build/launcher/sensornet --version >/dev/null 2>&1 && break; sleep 15; done
    started=$SECONDS
    if build/launcher/sensornet launch scenarios/default.yaml --episodes 4 --time-scale 5 --seed 7 \
      --run-id "native-$$" --report "$work/native.json" --no-html >"$work/native.log" 2>&1; then
      ok=true
      break
    fi
    docker_host_log "the native run failed (attempt $attempt): retrying in 30 s"
    tail -n 5 "$work/native.log" >&2
    sleep 30
  done
  if ! $ok; then
    tail -n 20 "$work/native.log" >&2
    docker_host_log "the native run failed"
    return 1
  fi
  docker_host_log "the same run natively (sensornet launch) over after $((SECONDS - started)) s"
}

docker_costs_match_native() {
  local work=$1 report=$2 status=${3:-completed}
  docker_native_report "$work" || return 1
  /usr/bin/python3 - "$report" "$work/native.json" "$docker_host_log_prefix" "$status" <<'PY'
import json, sys
c, n = (json.load(open(p)) for p in sys.argv[1:3])
who = sys.argv[3]
assert c["status"] == sys.argv[4], (c["status"], c["faults"])
episodes = c["per_episode"]
assert [e["episode"] for e in episodes] == [0, 1, 2, 3], [e["episode"] for e in episodes]
assert all(e["complete"] for e in episodes)
sent = sum(s["sent"] for s in c["sensors"]); received = sum(s["received"] for s in c["sensors"])
assert sent == received > 0, (sent, received)
assert len(n["per_episode"]) == 4
diffs = [abs(a["realized_cost"] - b["realized_cost"]) / abs(b["realized_cost"])
         for a, b in zip(episodes, n["per_episode"])]
for a, b, d in zip(episodes, n["per_episode"], diffs):
    print(f"{who}:   episode {a['episode']}: realized cost {a['realized_cost']:.12g}, "
          f"native {b['realized_cost']:.12g}, relative difference {d:.2g}", file=sys.stderr)
assert max(diffs) <= 1e-9, max(diffs)
print(f"{who}: the costs equal the native run's (largest relative difference {max(diffs):.2g}); "
      f"{received} of {sent} measurements fused", file=sys.stderr)
PY
}

docker_ready_after() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import datetime, sys
for line in open(sys.argv[1]):
    if "sensors and the fusion center are ready" in line:
        stamp = line.split()[0]  # RFC 3339 with nanoseconds: cut to microseconds
        day, frac = stamp.rstrip("Z").split(".")
        at = datetime.datetime.fromisoformat(f"{day}.{frac[:6]}+00:00").timestamp()
        print(f"{at - float(sys.argv[2]):.1f}")
        break
else:
    print("not logged")
PY
}
