#!/usr/bin/env bash
# Installs what is missing, builds, and emulates the default scenario as separate processes
# over Cyclone DDS on loopback: coordinator, one sensor_agent per sensor, fusion center; 20
# episodes at 10x real time, then the realized cost against the bracket of the schedule.
#   scripts/demo.sh [SCENARIO.yaml] [extra `sensornet launch` flags]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)" --target sensornet coordinator fusion_center sensor_agent \
  >/dev/null
scenario=${1:-scenarios/default.yaml}
shift || true
exec build/launcher/sensornet launch "$scenario" --episodes 20 --time-scale 10 "$@"
