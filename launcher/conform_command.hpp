#pragma once
// `sensornet conform sensor [options] -- PROGRAM ARGS`: runs a launched run with the user's
// program in a sensor's role and judges it rule by rule against docs/wire-protocol.md
// (conform/conform_run.hpp): a table, JUnit with --junit, exit 0 only when every rule holds.

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addConformCommand(CLI::App& app);

}  // namespace sensornet::launcher
