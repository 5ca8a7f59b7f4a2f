#pragma once
// `sensornet replan`: asks the coordinator of a running emulation for a new schedule (another
// surrogate, sensors excluded, a new budget, or a schedule file) and prints its answer.

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addReplanCommand(CLI::App& app);

}  // namespace sensornet::launcher
