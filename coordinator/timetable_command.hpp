#pragma once
// `coordinator timetable`: optimal deterministic measurement instants for a scalar Brownian
// motion (second paper), printed as text or JSON.

#include "sensornet/io/command_line.hpp"

namespace sensornet::coordinator {

Subcommand addTimetableCommand(CLI::App& app);

}  // namespace sensornet::coordinator
