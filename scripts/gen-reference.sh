#!/usr/bin/env bash
# Writes the command reference, docs/reference/commands.md, from the programs' own --help:
# one section per program and subcommand (found from each --help's "SUBCOMMANDS" list, so a new
# subcommand gets its section by itself), the help text verbatim in a code block.
#
#   scripts/gen-reference.sh BUILD_DIR [OUT]     # OUT: default docs/reference/commands.md; - for stdout
#
# The test `docs.CommandReference` (tests/CMakeLists.txt) runs this into a temporary file and
# fails with the diff when the committed page differs: after changing an option, run
#   scripts/gen-reference.sh build
# and commit the page. The programs run in a fixed environment (no SENSORNET_* or CYCLONEDDS_*
# variables, C locale, fixed HOME and scratch paths), so the text does not depend on who runs it;
# any path of the build or source folder left in a help text is written as BUILD_DIR / SOURCE_DIR.
set -euo pipefail

if [[ $# -lt 1 || $# -gt 2 ]]; then
  echo "usage: scripts/gen-reference.sh BUILD_DIR [OUT]" >&2
  exit 2
fi
source_dir=$(cd "$(dirname "$0")/.." && pwd)
build_dir=$(cd "$1" && pwd)
out=${2:-$source_dir/docs/reference/commands.md}

programs=(
  "sensornet:launcher/sensornet"
  "coordinator:coordinator/coordinator"
  "fusion_center:fusion_center/fusion_center"
  "sensor_agent:sensor_agent/sensor_agent"
)

# One program's --help (standard output only: a sanitizer build's reports go to standard error)
# in a fixed environment; the build and source folders replaced by names.
help_text() {
  local binary=$1
  shift
  env -i PATH=/usr/bin:/bin HOME=/nonexistent LC_ALL=C COLUMNS=100 ASAN_OPTIONS=detect_leaks=0 \
    "$binary" "$@" --help 2>/dev/null </dev/null |
    sed -e "s|$build_dir|BUILD_DIR|g" -e "s|$source_dir|SOURCE_DIR|g"
}

# The subcommand names a CLI11 help lists under "SUBCOMMANDS:" (or "Subcommands:").
subcommands_of() {
  awk '
    /^(SUBCOMMANDS|Subcommands):[[:space:]]*$/ { inside = 1; next }
    inside && /^[^[:space:]]/ { inside = 0 }
    inside && /^  [a-z][a-z0-9_-]*([[:space:]]|$)/ { print $1 }
  '
}

# A section for one command, then one for each of its subcommands, recursively.
emit() {
  local name=$1 binary=$2
  shift 2
  local text
  text=$(help_text "$binary" "$@")
  local title="$name${*:+ $*}"
  printf '## `%s`\n\n```text\n%s\n```\n\n' "$title" "$text"
  local sub
  for sub in $(printf '%s\n' "$text" | subcommands_of); do
    emit "$name" "$binary" "$@" "$sub"
  done
}

generate() {
  cat <<'EOF'
# Command reference

[Reference](../README.md). Every program's and subcommand's options, exactly as its `--help`
prints them. **Generated** by `scripts/gen-reference.sh BUILD_DIR` from the built programs; do
not edit by hand. The test `docs.CommandReference` fails when this page and the programs
disagree: after changing an option, run `scripts/gen-reference.sh build` and commit the page.
What the options mean in use is in the [guide](../guide/README.md); the conventions every
program shares (`--json`, exit status 2 on bad input, how output folders are made) in
[command-line conventions](cli.md).

EOF
  local entry name path
  printf 'Programs: '
  local first=1
  for entry in "${programs[@]}"; do
    name=${entry%%:*}
    [[ $first == 1 ]] || printf ', '
    printf '`%s`' "$name"
    first=0
  done
  printf '.\n\n'
  for entry in "${programs[@]}"; do
    name=${entry%%:*}
    path=$build_dir/${entry#*:}
    if [[ ! -x $path ]]; then
      echo "gen-reference: no program $path (build it first)" >&2
      exit 1
    fi
    emit "$name" "$path"
  done
}

# cat -s: never two blank lines in a row (a help text that ends in one).
if [[ $out == - ]]; then
  generate | cat -s
else
  tmp=$(mktemp "$out.XXXXXX")
  trap 'rm -f "$tmp"' EXIT
  generate | cat -s >"$tmp"
  chmod 0644 "$tmp"
  mv "$tmp" "$out"
  trap - EXIT
fi
