#!/usr/bin/env bash
# Installs the Debian 12 packages sensornet needs to build, test and run: only those missing,
# so it takes a second when everything is already there. Needs root (or sudo) to install.
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config
  cyclonedds-dev cyclonedds-tools
  libeigen3-dev libspdlog-dev libfmt-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  coinor-libipopt-dev liblapack-dev libblas-dev  # IPOPT's CMake link line names -llapack -lblas
  libgtest-dev libgmock-dev docker-compose
  fastddsgen libfastrtps-dev  # a second DDS vendor: the interoperability test (Fast DDS 2.9)
  chromium  # headless, for the report page's browser test
  openssl libssl-dev  # secured runs: `sensornet pki init` runs openssl; certificates checked with libcrypto
  iproute2 procps  # multi-host tests and scripts/netns-hosts.sh (ip netns, veth); pgrep/ps in tests
  python3-dev python3-pybind11 pybind11-dev python3-pytest  # the Python module, its pytest fixture
)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done
if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "install-deps: installing ${missing[*]}" >&2
sudo=()
if [[ "$(id -u)" -ne 0 ]]; then
  sudo=(sudo)
fi
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends \
  "${missing[@]}"
