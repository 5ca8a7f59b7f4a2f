#!/usr/bin/env bash
# docker/ on a real Docker Engine: the image (docker/Dockerfile), compose (docker/compose.yaml)
# and a swarm stack (the same file with docker/compose.swarm.yaml over it). CI runs it after the
# main suite (.ci/run).
#
#   scripts/test-containers.sh                 everything below
#   scripts/test-containers.sh --keep          leave the images it built for a look
#   scripts/test-containers.sh --image NAME    test an image built before instead of building
#
# 1. builds the image and prints its size;
# 2. compose, a clean run (4 episodes, seed 7): every container leaves the run, the coordinator
#    exits 0, the report in the volume says completed with every episode complete and every
#    measurement fused, report.jsonl and report.html beside it, and every realized cost equals
#    that of a native `sensornet launch` of the same scenario and seed (build/, relative 1e-9:
#    the image is built without -march=native);
# 3. compose with faults (8 episodes): once episode 2 is reported, the container of sensors 3-5
#    is killed (a sensor death: the coordinator learns it from DDS liveliness and re-plans, so
#    a later version gives sensors 3-5 rate zero) and the fusion center's process is killed (its
#    restart policy brings it back, and it resumes from the episode log: every episode is in the
#    report, the one it missed marked fusion_center_restarted); the report is degraded, exit 3
#    in the run-outcome table, and names sensor_died for 3, 4 and 5 and the restart;
# 4. a single-node swarm (made for the test when this Engine is in none, and left again):
#    `docker stack deploy` runs 4 episodes to the end over the overlay network with the sensors
#    as one replicated service of two tasks; the report says completed; the time from deploy to
#    "all 6 sensors ... ready" is printed;
# 5. removes every container, network, volume, stack and image it made, stops the dockerd it
#    started (scripts/docker-host.sh), also on failure or Ctrl-C.
# Needs root (dockerd, packages). Exit status 0 when every check passed, 1 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."

docker_host_log_prefix=test-containers
source scripts/docker-host.sh
log() { docker_host_log "$*"; }
fail() { log "FAIL: $*"; exit 1; }

keep=false
given_image=""
while (($# > 0)); do
  case "$1" in
    --keep) keep=true ;;
    --image) given_image=${2:?--image needs a name}; shift ;;
    *) echo "usage: scripts/test-containers.sh [--keep] [--image NAME]" >&2; exit 2 ;;
  esac
  shift
done

work=$(mktemp -d /tmp/sensornet-containers.XXXXXX)
tag=${given_image:-sensornet-test:$$}
projects=()
stack=""
swarm_made=false
gwbridge_made=false
cleanup() {
  local status=$?
  local project
  for project in "${projects[@]}"; do
    compose -p "$project" -f docker/compose.yaml down -v --remove-orphans >/dev/null 2>&1 || true
  done
  if [[ -n "$stack" ]]; then
    docker stack rm "$stack" >/dev/null 2>&1 || true
    local _ label="label=com.docker.stack.namespace=$stack"
    for _ in $(seq 1 100); do  # the tasks' containers go asynchronously, then the network
      [[ -z "$(docker ps -aq -f "$label")" ]] && \
        ! docker network inspect "${stack}_sensornet" >/dev/null 2>&1 && break
      sleep 0.3
    done
    docker ps -aq -f "$label" | xargs -r docker rm -f >/dev/null 2>&1 || true
    docker volume rm "${stack}_reports" >/dev/null 2>&1 || true
  fi
  if $swarm_made; then
    docker swarm leave --force >/dev/null 2>&1 || true
    # The bridge `swarm init` made for the tasks' way out, unless it was there before.
    $gwbridge_made && docker network rm docker_gwbridge >/dev/null 2>&1 || true
  fi
  if ! $keep && [[ -z "$given_image" ]]; then
    docker rmi -f "$tag" >/dev/null 2>&1 || true
    # The build stage's layers too (untagged images the build left): every image that was not
    # there before the build.
    if [[ -f "$work/images-before" ]]; then
      docker images -aq --no-trunc | sort -u | comm -13 "$work/images-before" - \
        | xargs -r docker rmi -f >/dev/null 2>&1 || true
    fi
  fi
  docker_host_down
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

docker_host_up "$work" docker.io debootstrap docker-compose || fail "no Docker Engine"
docker_base_image "$work" || fail "no Debian 12 base image"

# `docker compose` (v2) where the CLI has it, else Debian's docker-compose (v1): the same file.
compose() {
  if docker compose version >/dev/null 2>&1; then docker compose "$@"; else docker-compose "$@"; fi
}

# ---- 1. the image ------------------------------------------------------------------------------
if [[ -z "$given_image" ]]; then
  docker images -aq --no-trunc | sort -u >"$work/images-before"
  log "building the image $tag (docker/Dockerfile; log: $work/build.log)"
  started=$SECONDS
  docker build -f docker/Dockerfile --build-arg "BASE_IMAGE=$docker_host_image" -t "$tag" . \
    >"$work/build.log" 2>&1 || { tail -n 30 "$work/build.log" >&2; fail "the image did not build"; }
  log "image built in $((SECONDS - started)) s"
fi
size=$(docker image inspect -f '{{.Size}}' "$tag")
log "image $tag: $((size / 1000000)) MB"
for program in sensornet coordinator fusion_center sensor_agent; do
  docker run --rm "$tag" "$program" --version >/dev/null || fail "$program is not on the image's PATH"
done
[[ "$(docker run --rm "$tag" id -u)" != 0 ]] || fail "the image runs as root"
for absent in g++ cc chromium docker-compose fastddsgen; do
  if docker run --rm "$tag" sh -c "command -v $absent" >/dev/null; then
    fail "the runtime image holds $absent"
  fi
done

# The report of a run in a volume: VOLUME FILE -> stdout.
from_volume() { docker run --rm -v "$1:/reports:ro" "$tag" cat "/reports/$2"; }

# A compose run (the caller lists PROJECT in `projects` for the cleanup); PROJECT, then the
# environment of docker/compose.yaml as NAME=VALUE.
compose_up() {
  local project=$1
  shift
  (
    export "$@" SENSORNET_IMAGE="$tag"
    compose -p "$project" -f docker/compose.yaml up --no-build >"$work/$project.log" 2>&1
  )
}

container_of() { compose -p "$1" -f docker/compose.yaml ps -q "$2"; }

# python3 checks on a report: REPORT SCRIPT (the report as `r`).
check_report() {
  python3 - "$1" "$2" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
exec(sys.argv[2])
PY
}

# ---- 2. compose: a clean run, against a native one -------------------------------------------
if [[ ! -x build/launcher/sensornet ]]; then
  log "building the native programs (build/) for the comparison"
  cmake -S . -B build -G Ninja >/dev/null && cmake --build build --target sensornet coordinator \
    fusion_center sensor_agent >/dev/null
fi
log "compose: a clean run of 4 episodes"
started=$SECONDS
project="sntclean$$"
projects+=("$project")
compose_up "$project" SENSORNET_RUN_ID="compose-clean-$$" SENSORNET_EPISODES=4 \
  SENSORNET_TIME_SCALE=5 SENSORNET_SEED=7 || { tail -n 30 "$work/$project.log" >&2; fail "compose up"; }
log "compose run over after $((SECONDS - started)) s"
code=$(docker inspect -f '{{.State.ExitCode}}' "$(container_of "$project" coordinator)")
[[ "$code" == 0 ]] || { tail -n 30 "$work/$project.log" >&2; fail "the coordinator exited $code"; }
from_volume "${project}_reports" report.json >"$work/clean.json"
from_volume "${project}_reports" report.jsonl >/dev/null || fail "no report.jsonl in the volume"
from_volume "${project}_reports" report.html >"$work/clean.html" || fail "no report page in the volume"
grep -q "<svg" "$work/clean.html" || fail "the report page in the volume has no plot"
started=$SECONDS
build/launcher/sensornet launch scenarios/default.yaml --episodes 4 --time-scale 5 --seed 7 \
  --run-id "native-$$" --report "$work/native.json" --no-html >"$work/native.log" 2>&1 \
  || { tail -n 20 "$work/native.log" >&2; fail "the native run"; }
log "the same run natively (sensornet launch) over after $((SECONDS - started)) s"
python3 - "$work/clean.json" "$work/native.json" <<'PY' || fail "the compose run's report"
import json, sys
c, n = (json.load(open(p)) for p in sys.argv[1:3])
assert c["status"] == "completed", (c["status"], c["faults"])
episodes = c["per_episode"]
assert [e["episode"] for e in episodes] == [0, 1, 2, 3], [e["episode"] for e in episodes]
assert all(e["complete"] for e in episodes)
sent = sum(s["sent"] for s in c["sensors"]); received = sum(s["received"] for s in c["sensors"])
assert sent == received > 0, (sent, received)
worst = max(abs(a["realized_cost"] - b["realized_cost"]) / abs(b["realized_cost"])
            for a, b in zip(episodes, n["per_episode"]))
assert len(n["per_episode"]) == 4 and worst <= 1e-9, worst
print(f"test-containers: compose costs equal the native run's (largest relative difference "
      f"{worst:.2g}); {received} measurements fused", file=sys.stderr)
PY

# ---- 3. compose with faults -------------------------------------------------------------------
log "compose: 8 episodes, sensors 3-5 killed and the fusion center killed after episode 2"
project="sntfault$$"
projects+=("$project")
run_id="compose-faults-$$"
(compose_up "$project" SENSORNET_RUN_ID="$run_id" SENSORNET_EPISODES=8 SENSORNET_TIME_SCALE=2 \
  SENSORNET_SEED=7) &
up_pid=$!
reported() {  # the episode log's count in the volume
  docker run --rm -v "${project}_reports:/reports:ro" "$tag" sh -c \
    'cat /reports/report.jsonl 2>/dev/null | wc -l'
}
for _ in $(seq 1 120); do
  (($(reported) >= 3)) && break
  sleep 1
done
(($(reported) >= 3)) || fail "episode 2 was not reported within 120 s"
docker kill "$(container_of "$project" sensors-3-5)" >/dev/null
fusion=$(container_of "$project" fusion-center)
# The fusion center's own process dies (not a `docker kill`, which the Engine takes as an
# operator's stop and does not restart): PID 1 is tini, the program its child.
kill -9 "$(pgrep -P "$(docker inspect -f '{{.State.Pid}}' "$fusion")")"
wait "$up_pid" || { tail -n 30 "$work/$project.log" >&2; fail "compose up with faults"; }
restarts=$(docker inspect -f '{{.RestartCount}}' "$fusion")
((restarts == 1)) || fail "the fusion center restarted $restarts times, not once"
code=$(docker inspect -f '{{.State.ExitCode}}' "$(container_of "$project" coordinator)")
[[ "$code" == 0 ]] || fail "the coordinator exited $code"
from_volume "${project}_reports" report.json >"$work/faults.json"
check_report "$work/faults.json" '
assert r["status"] == "degraded", r["status"]
assert [e["episode"] for e in r["per_episode"]] == list(range(8)), [e["episode"] for e in r["per_episode"]]
kinds = [f["kind"] for f in r["faults"]]
died = sorted(f["sensor"] for f in r["faults"] if f["kind"] == "sensor_died")
assert died == [3, 4, 5], (died, kinds)
assert any(f["kind"] == "restarted" and f["process"] == "fusion_center" for f in r["faults"]), kinds
zero = [v["version"] for v in r["schedule_versions"]
        if v["version"] > 1 and all(max(row[j] for row in v["rates"]) == 0 for j in (3, 4, 5))]
assert zero, "no version after the death gives sensors 3-5 rate zero"
print("test-containers: faults:", ", ".join(sorted(set(kinds))), "; re-planned in version(s)", zero,
      "; complete episodes", sum(e["complete"] for e in r["per_episode"]), "of 8", file=sys.stderr)
' || fail "the report of the run with faults"

# ---- 4. a swarm -------------------------------------------------------------------------------
if [[ "$(docker info -f '{{.Swarm.LocalNodeState}}')" != active ]]; then
  docker network inspect docker_gwbridge >/dev/null 2>&1 || gwbridge_made=true
  docker swarm init --advertise-addr 127.0.0.1 >/dev/null || fail "docker swarm init"
  swarm_made=true
fi
stack="sntswarm$$"
log "swarm: docker stack deploy $stack, 4 episodes"
started=$SECONDS
deployed_at=$(date +%s.%N)
SENSORNET_IMAGE="$tag" SENSORNET_RUN_ID="swarm-$$" SENSORNET_EPISODES=4 SENSORNET_TIME_SCALE=5 \
  SENSORNET_SEED=7 docker stack deploy -c docker/compose.yaml -c docker/compose.swarm.yaml \
  "$stack" >"$work/stack.log" 2>&1 || { cat "$work/stack.log" >&2; fail "docker stack deploy"; }
task_state() { docker service ps --no-trunc -f desired-state=shutdown -f desired-state=running \
  --format '{{.CurrentState}}' "${stack}_coordinator" 2>/dev/null | head -n 1; }
for _ in $(seq 1 240); do
  [[ "$(task_state)" == Complete* || "$(task_state)" == Failed* ]] && break
  sleep 0.5
done
docker service logs --raw --timestamps "${stack}_coordinator" >"$work/swarm-coordinator.log" 2>&1 || true
[[ "$(task_state)" == Complete* ]] || { tail -n 20 "$work/swarm-coordinator.log" >&2; fail "the swarm's coordinator: $(task_state)"; }
for _ in $(seq 1 60); do  # the fusion center writes the report once the run has ended
  from_volume "${stack}_reports" report.json >"$work/swarm.json" 2>/dev/null && break
  sleep 0.5
done
check_report "$work/swarm.json" '
assert r["status"] == "completed", (r["status"], r["faults"])
assert len(r["per_episode"]) == 4 and all(e["complete"] for e in r["per_episode"])
' || fail "the swarm run's report"
ready=$(python3 - "$work/swarm-coordinator.log" "$deployed_at" <<'PY'
import datetime, sys
for line in open(sys.argv[1]):
    if "sensors and the fusion center are ready" in line:
        stamp = line.split()[0]  # RFC 3339 with nanoseconds: cut to microseconds
        day, frac = stamp.rstrip("Z").split(".")
        at = datetime.datetime.fromisoformat(f"{day}.{frac[:6]}+00:00").timestamp()
        print(f"{at - float(sys.argv[2]):.1f} s")
        break
else:
    print("not logged")
PY
)
log "swarm run completed in $((SECONDS - started)) s; every peer ready $ready after the deploy"
log "every check passed"
