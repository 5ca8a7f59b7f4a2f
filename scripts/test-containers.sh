#!/usr/bin/env bash
# docker/ on a real Docker Engine: the image (docker/Dockerfile), compose (docker/compose.yaml)
# and a swarm stack (the same file with docker/compose.swarm.yaml over it). CI runs it after the
# main suite (.ci/run).
#
#   scripts/test-containers.sh                 everything below
#   scripts/test-containers.sh --keep          leave the images it built for a look
#   scripts/test-containers.sh --tag NAME      build the image as NAME and keep it (CI passes it
#                                              on to scripts/test-swarm.sh)
#   scripts/test-containers.sh --image NAME    test an image built before instead of building
#                                              (kept; removed too with --drop-image)
#
# 1. builds the image and prints its size;
# 2. compose, a clean run over the files of an interrupted one: a first `up` (run nonce A) is
#    killed whole (`compose kill`) once episode 1 is reported, leaving an episode log without a
#    report and a coordinator journal in the volume; a second `up` of the same project (run nonce
#    B) must not resume them: both programs log that they start afresh over an earlier
#    deployment's files, every container leaves the run, the coordinator exits 0, the report in
#    the volume says completed with no fault, every episode complete and every measurement fused,
#    report.jsonl and report.html beside it, and every realized cost equals that of a native
#    `sensornet launch` of the same scenario and seed (build/, relative 1e-9: the image is built
#    without -march=native);
# 3. compose with faults (8 episodes): once episode 2 is reported, the container of sensors 3-5
#    is killed (a sensor death: the coordinator learns it from DDS liveliness and re-plans, so
#    a later version gives sensors 3-5 rate zero) and the fusion center's process is killed (its
#    restart policy brings it back, and it resumes from the episode log: every episode is in the
#    report, the one it missed marked fusion_center_restarted); the report is degraded, exit 3
#    in the run-outcome table, and names sensor_died for 3, 4 and 5 and the restart;
# 3b. compose with the coordinator killed (4 episodes): once episode 1 is reported its process is
#    killed; `restart: on-failure` brings it back and it resumes from its journal in the volume
#    (same run nonce): it restarted once and exits 0, the report is degraded (exit 3 in the
#    run-outcome table) with exactly one fault, the coordinator's `restarted`, and every episode
#    is complete with the native run's cost, as when the launcher restarts a killed coordinator;
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

docker_test_options "scripts/test-containers.sh [--keep | --tag NAME | --image NAME [--drop-image]]" "$@"

work=$(mktemp -d /tmp/sensornet-containers.XXXXXX)
tag=$test_image
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
  $remove_image && docker_runtime_image_remove "$work" "$tag"
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
if $build_image; then
  docker_runtime_image "$work" "$tag" || fail "the image"
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
# The episode log's count in PROJECT's volume.
reported() {
  docker run --rm -v "$1_reports:/reports:ro" "$tag" sh -c 'cat /reports/report.jsonl 2>/dev/null | wc -l'
}
# Waits until PROJECT's episode log has N entries (at most 120 s).
await_reported() {
  local _
  for _ in $(seq 1 120); do
    (($(reported "$1") >= $2)) && return 0
    sleep 1
  done
  fail "episode $(($2 - 1)) of $1 was not reported within 120 s"
}
# The PID, on this machine, of PROGRAM in SERVICE's container of PROJECT (PID 1 there is tini).
program_pid() { pgrep -P "$(docker inspect -f '{{.State.Pid}}' "$(container_of "$1" "$2")")"; }

project="sntclean$$"
projects+=("$project")
log "compose: a first up (run nonce A) killed whole once episode 1 is reported"
(compose_up "$project" SENSORNET_RUN_ID="compose-clean-$$" SENSORNET_EPISODES=4 \
  SENSORNET_TIME_SCALE=2 SENSORNET_SEED=7 SENSORNET_RUN_NONCE="first-$$") &
up_pid=$!
await_reported "$project" 2
compose -p "$project" -f docker/compose.yaml kill >/dev/null 2>&1
wait "$up_pid" || true
mv "$work/$project.log" "$work/$project-first.log"
log "compose: a clean run of 4 episodes over its files (run nonce B)"
started=$SECONDS
compose_up "$project" SENSORNET_RUN_ID="compose-clean-$$" SENSORNET_EPISODES=4 \
  SENSORNET_TIME_SCALE=5 SENSORNET_SEED=7 SENSORNET_RUN_NONCE="second-$$" \
  || { tail -n 30 "$work/$project.log" >&2; fail "compose up"; }
log "compose run over after $((SECONDS - started)) s"
docker logs "$(container_of "$project" coordinator)" >"$work/second-coordinator.log" 2>&1
docker logs "$(container_of "$project" fusion-center)" >"$work/second-fusion.log" 2>&1
grep -q "journal at .* is an earlier deployment's (run nonce 'first-$$', this one 'second-$$')" \
  "$work/second-coordinator.log" || fail "the coordinator did not say it started afresh over the first up's journal"
grep -q "episode log beside .* is an earlier deployment's (run nonce 'first-$$'" \
  "$work/second-fusion.log" || fail "the fusion center did not say it started afresh over the first up's log"
code=$(docker inspect -f '{{.State.ExitCode}}' "$(container_of "$project" coordinator)")
[[ "$code" == 0 ]] || { tail -n 30 "$work/$project.log" >&2; fail "the coordinator exited $code"; }
from_volume "${project}_reports" report.json >"$work/clean.json"
from_volume "${project}_reports" report.jsonl >/dev/null || fail "no report.jsonl in the volume"
from_volume "${project}_reports" report.html >"$work/clean.html" || fail "no report page in the volume"
grep -q "<svg" "$work/clean.html" || fail "the report page in the volume has no plot"
docker_costs_match_native "$work" "$work/clean.json" || fail "the compose run's report"
check_report "$work/clean.json" 'assert r["faults"] == [], r["faults"]' \
  || fail "the clean run over an earlier up's files has faults"

# ---- 3. compose with faults -------------------------------------------------------------------
log "compose: 8 episodes, sensors 3-5 killed and the fusion center killed after episode 2"
project="sntfault$$"
projects+=("$project")
run_id="compose-faults-$$"
(compose_up "$project" SENSORNET_RUN_ID="$run_id" SENSORNET_EPISODES=8 SENSORNET_TIME_SCALE=2 \
  SENSORNET_SEED=7) &
up_pid=$!
await_reported "$project" 3
docker kill "$(container_of "$project" sensors-3-5)" >/dev/null
fusion=$(container_of "$project" fusion-center)
# The fusion center's own process dies (not a `docker kill`, which the Engine takes as an
# operator's stop and does not restart): PID 1 is tini, the program its child.
kill -9 "$(program_pid "$project" fusion-center)"
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

# ---- 3b. compose with the coordinator killed --------------------------------------------------
log "compose: 4 episodes, the coordinator killed after episode 1"
project="sntcoord$$"
projects+=("$project")
(compose_up "$project" SENSORNET_RUN_ID="compose-coordinator-$$" SENSORNET_EPISODES=4 \
  SENSORNET_TIME_SCALE=2 SENSORNET_SEED=7 SENSORNET_RUN_NONCE="coordinator-$$") &
up_pid=$!
await_reported "$project" 2
coordinator=$(container_of "$project" coordinator)
kill -9 "$(program_pid "$project" coordinator)"
wait "$up_pid" || { tail -n 30 "$work/$project.log" >&2; fail "compose up with the coordinator killed"; }
restarts=$(docker inspect -f '{{.RestartCount}}' "$coordinator")
((restarts == 1)) || fail "the coordinator restarted $restarts times, not once"
code=$(docker inspect -f '{{.State.ExitCode}}' "$coordinator")
[[ "$code" == 0 ]] || { tail -n 30 "$work/$project.log" >&2; fail "the restarted coordinator exited $code"; }
# The container's log holds both lives (compose's own output may miss a restarted one's lines).
docker logs "$coordinator" >"$work/coordinator-lives.log" 2>&1
grep -q "resuming from /reports/coordinator-state.json" "$work/coordinator-lives.log" \
  || { tail -n 20 "$work/coordinator-lives.log" >&2; fail "the restarted coordinator did not resume"; }
from_volume "${project}_reports" report.json >"$work/coordinator.json"
docker_costs_match_native "$work" "$work/coordinator.json" degraded \
  || fail "the run with the coordinator killed"
check_report "$work/coordinator.json" '
kinds = [(f["kind"], f["process"], f.get("survived")) for f in r["faults"]]
assert kinds == [("restarted", "coordinator", True)], kinds
print("test-containers: the coordinator killed:", r["faults"][0]["detail"], file=sys.stderr)
' || fail "the faults of the run with the coordinator killed"

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
lat = r.get("latency_s") or {}
median, p99 = lat.get("median"), lat.get("p99")
if median is not None:
    print(f"test-containers: latency publish to fusion on one node: median "
          f"{median * 1e3:.3f} ms, p99 {p99 * 1e3:.3f} ms", file=sys.stderr)
' || fail "the swarm run's report"
ready=$(docker_ready_after "$work/swarm-coordinator.log" "$deployed_at")
log "swarm run completed in $((SECONDS - started)) s; every peer ready $ready s after the deploy"
log "every check passed"
