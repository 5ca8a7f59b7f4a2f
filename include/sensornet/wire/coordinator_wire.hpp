#pragma once
// The coordinator core's events from their DDS samples, and its episode controls as samples
// (idl/sensornet.idl): what `coordinator serve` reads and writes, field by field, without the
// loop that carries them.
//
//   core.onCommand(commandOf(*received.sample, CommandSender::Launcher), now);
//   core.onReport(reportOf(*received.sample), now);
//   writer.write(wireControl(action.control, run_id));   // borrows from both: keep them alive

#include <string>

#include "sensornet/dds/topics.hpp"
#include "sensornet/emulator/coordinator_core.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/wire/messages.hpp"

namespace sensornet::wire {

// Unknown for a kind this program does not know (a newer sender's).
[[nodiscard]] emulator::CommandKind commandKindOf(sensornet_CommandKind kind);
[[nodiscard]] emulator::CommandEvent commandOf(const sensornet_Command& c,
                                               emulator::CommandSender sender);
[[nodiscard]] emulator::ReportEvent reportOf(const sensornet_Report& r);
[[nodiscard]] emulator::FusionStateEvent fusionStateOf(const sensornet_FusionState& s);
// The episode controls' codec is messages.hpp's (wireControl, controlOf).

}  // namespace sensornet::wire
