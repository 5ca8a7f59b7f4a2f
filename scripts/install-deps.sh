#!/usr/bin/env bash
# Installs the Debian 12 packages sensornet needs to build, test and run: only those missing,
# so it takes a second when everything is already there. Needs root (or sudo) to install.
set -euo pipefail

# What building the programs needs (cmake -DSENSORNET_BUILD_TESTS=OFF -DSENSORNET_BUILD_BENCH=OFF
# -DSENSORNET_PYTHON=OFF): the build stage of docker/Dockerfile.
build_packages=(
  cmake ninja-build g++ pkg-config
  cyclonedds-dev cyclonedds-tools
  libeigen3-dev libspdlog-dev libfmt-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  coinor-libipopt-dev liblapack-dev libblas-dev  # IPOPT's CMake link line names -llapack -lblas
  libssl-dev  # certificates checked with libcrypto
)
# What the built programs load and run, and nothing else: the runtime stage of docker/Dockerfile.
# Cyclone with its security plugins, spdlog, fmt, yaml-cpp, IPOPT (with lapack, blas, MUMPS),
# libcrypto; openssl, which `sensornet pki init` runs; tini, a PID 1 for containers.
runtime_packages=(
  libddsc0debian libspdlog1.10 libfmt9 libyaml-cpp0.7 coinor-libipopt1v5 libssl3 openssl tini
)
# Everything else the tests and the documented features use.
packages=(
  "${build_packages[@]}"
  libgtest-dev libgmock-dev docker-compose
  fastddsgen libfastrtps-dev  # a second DDS vendor: the interoperability test (Fast DDS 2.9)
  chromium  # headless, for the report page's browser test
  openssl  # secured runs: `sensornet pki init` runs openssl
  iproute2 procps  # multi-host tests and scripts/netns-hosts.sh (ip netns, veth); pgrep/ps in tests
  iptables faketime  # the chaos checker's network faults (partitions, loss); a host's clock offset
  python3-dev python3-pybind11 pybind11-dev python3-pytest  # the Python module, its pytest fixture
  python3-numpy  # sensornet.World and the math give numpy arrays
  python3-pandas  # sensornet.Report.episodes is a DataFrame
  python3-jsonschema  # the tests check real reports against docs/report.schema.json
)
# --tests (scripts/test.sh): also what only the tests use. Prometheus' server scrapes a run's
# /metrics and promtool checks the exposition; @mcap/core (npm), the reference MCAP reader, reads
# recordings. A machine with node from elsewhere (NodeSource's nodejs bundles npm) keeps it.
# --build: only what building the programs needs; --runtime: only what running them needs.
for_tests=false
case "${1:-}" in
  "") ;;
  --tests) for_tests=true ;;
  --build) packages=("${build_packages[@]}") ;;
  --runtime) packages=("${runtime_packages[@]}") ;;
  *)
    echo "usage: scripts/install-deps.sh [--tests|--build|--runtime]" >&2
    exit 2
    ;;
esac
if $for_tests; then
  packages+=(prometheus)
  if ! command -v node >/dev/null; then packages+=(nodejs); fi
  if ! command -v npm >/dev/null; then packages+=(npm); fi
fi
# Where the npm packages of the tests go (tests/CMakeLists.txt looks there).
node_prefix=/opt/sensornet-node
mcap_core_version=2.2.2

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done
sudo=()
if [[ "$(id -u)" -ne 0 ]]; then
  sudo=(sudo)
fi
if ((${#missing[@]} > 0)); then
  echo "install-deps: installing ${missing[*]}" >&2
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}"
fi
if $for_tests && [[ ! -f "$node_prefix/node_modules/@mcap/core/package.json" ]]; then
  echo "install-deps: installing @mcap/core $mcap_core_version (npm) into $node_prefix" >&2
  "${sudo[@]}" mkdir -p "$node_prefix"
  for attempt in 1 2; do  # the registry is the network's: one retry
    if "${sudo[@]}" npm install --prefix "$node_prefix" --no-audit --no-fund --silent \
      "@mcap/core@$mcap_core_version"; then
      break
    fi
    if ((attempt == 2)); then
      echo "install-deps: error: npm could not install @mcap/core (see above)" >&2
      exit 1
    fi
    sleep 5
  done
fi
