#!/usr/bin/env bash
# Installs what is missing, builds, and evaluates the default scenario: the surrogate bracket
# and a Monte Carlo estimate of the realized cost of the uniform schedule.
#   scripts/demo.sh [SCENARIO.yaml] [extra fusion_center evaluate flags]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j "$(nproc)" --target fusion_center coordinator >/dev/null
scenario=${1:-scenarios/default.yaml}
shift || true
exec build/fusion_center/fusion_center evaluate --scenario "$scenario" --runs 4000 "$@"
