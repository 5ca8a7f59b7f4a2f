#pragma once
// `coordinator serve`: the coordinator of one emulation run. It publishes the scenario and the
// planned schedule, waits for the sensors and the fusion center, runs the episodes one after
// the other on the emulated clock, answers live commands (re-plan, exclude sensors, change the
// budget, adopt a schedule file) with new schedule versions, and shuts the run down.

#include "sensornet/io/command_line.hpp"

namespace sensornet::coordinator {

Subcommand addServeCommand(CLI::App& app);

}  // namespace sensornet::coordinator
