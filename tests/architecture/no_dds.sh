#!/usr/bin/env bash
# A library that must stay free of DDS: none of its sources or headers includes a DDS header (the
# Cyclone C API, sensornet's DDS layer or the IDL's generated types), and its archive calls
# nothing of Cyclone or of the DDS layer.
#
#   tests/architecture/no_dds.sh LIBRARY.a SOURCE_DIR HEADER_DIR
#
# Exit status 0 when free of DDS, 1 with each offending line otherwise, 2 on bad arguments.
set -uo pipefail
(($# == 3)) || { echo "usage: no_dds.sh LIBRARY.a SOURCE_DIR HEADER_DIR" >&2; exit 2; }
library=$1 sources=$2 headers=$3
for path in "$library" "$sources" "$headers"; do
  [[ -e "$path" ]] || { echo "no_dds.sh: $path does not exist" >&2; exit 2; }
done
status=0
includes=$(grep -rnE '^\s*#\s*include\s*[<"](dds/|sensornet/dds/|sensornet\.h[">])' \
  "$sources" "$headers" --include='*.cpp' --include='*.hpp' --include='*.h')
if [[ -n "$includes" ]]; then
  echo "includes of DDS headers:"
  echo "$includes"
  status=1
fi
# Undefined symbols the archive's objects need: Cyclone's C API is dds_*/ddsi_*/ddsrt_*, the
# DDS layer is namespace sensornet::dds, the IDL's type descriptors are sensornet_*_desc.
calls=$(nm --undefined-only --demangle "$library" 2>/dev/null |
  grep -E ' U (dds_|ddsi_|ddsrt_|sensornet::dds::|sensornet_[A-Za-z]+_desc)' | sort -u)
if [[ -n "$calls" ]]; then
  echo "$library calls into DDS:"
  echo "$calls"
  status=1
fi
if ((status == 0)); then
  echo "$(basename "$library"): no DDS header included, no DDS symbol needed"
fi
exit "$status"
