#pragma once
// `sensornet status`: what the sensors of a running emulation say about themselves (state,
// episode, schedule version, current rate, measurements sent, process) and the latest schedule.

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addStatusCommand(CLI::App& app);

}  // namespace sensornet::launcher
