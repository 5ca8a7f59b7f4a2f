#pragma once
// `sensornet launch SCENARIO`: runs one emulation on this host. Starts the fusion center, the
// sensor agents (K sensors per process) and the coordinator as separate processes, shows one
// progress line per episode, stops every process it started (also on Ctrl-C, a failing child
// or --timeout), and prints the realized cost against the bracket from the final report.

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addLaunchCommand(CLI::App& app);

}  // namespace sensornet::launcher
