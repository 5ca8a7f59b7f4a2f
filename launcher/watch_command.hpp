#pragma once
// `sensornet watch [--run-id ID]`: a live view of a running emulation from the topics any DDS
// tool can read (Scenario, Schedule, EpisodeControl, SensorStatus, Report; it writes nothing).
// On a terminal it redraws a screen four times a second: episode and progress, the schedule
// version in force, the running mean against the bracket, latency, and per sensor its state,
// rate, sent and received. Otherwise it prints plain lines, one per change (an episode started
// or reported, a sensor's state, a new schedule version), so that it can be logged. It exits 0
// when the run shuts down (after its last reports and its sensors' last words, or a short
// grace), 1 when no run answers within --wait or the run's coordinator leaves
// without shutting it down.

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addWatchCommand(CLI::App& app);

}  // namespace sensornet::launcher
