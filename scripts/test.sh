#!/usr/bin/env bash
# Installs what is missing, builds everything with warnings as errors, and runs every test.
#   scripts/test.sh              the normal build (build/) and all its tests
#   scripts/test.sh --sanitize   the same with AddressSanitizer + UBSan (build-asan/)
#   scripts/test.sh --all        both, one after the other (what CI runs)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --tests

run_suite() {
  local build_dir=$1
  shift
  local started=$SECONDS
  cmake -S . -B "$build_dir" -G Ninja -DSENSORNET_WERROR=ON "$@" >/dev/null
  cmake --build "$build_dir" -j "$(nproc)"
  echo "test.sh: $build_dir built in $((SECONDS - started)) s" >&2
  started=$SECONDS
  ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" --timeout 600
  echo "test.sh: $build_dir tests ran in $((SECONDS - started)) s" >&2
}

case "${1:-}" in
  "") run_suite build -DCMAKE_BUILD_TYPE=Release ;;
  --sanitize) run_suite build-asan -DCMAKE_BUILD_TYPE=Debug -DSENSORNET_SANITIZE=ON ;;
  --all)
    run_suite build -DCMAKE_BUILD_TYPE=Release
    run_suite build-asan -DCMAKE_BUILD_TYPE=Debug -DSENSORNET_SANITIZE=ON
    ;;
  *)
    echo "usage: scripts/test.sh [--sanitize|--all]" >&2
    exit 2
    ;;
esac
