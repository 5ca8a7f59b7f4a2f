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

namespace sensornet::emulator {

// Unknown for a kind this program does not know (a newer sender's).
[[nodiscard]] CommandKind commandKindOf(sensornet_CommandKind kind);
[[nodiscard]] CommandEvent commandOf(const sensornet_Command& c, CommandSender sender);
[[nodiscard]] ReportEvent reportOf(const sensornet_Report& r);
[[nodiscard]] FusionStateEvent fusionStateOf(const sensornet_FusionState& s);
[[nodiscard]] sensornet_EpisodeCommand episodeCommandOf(ControlKind kind);
// An EpisodeControl sample borrowing from `control` and `run_id` (which must outlive it).
[[nodiscard]] sensornet_EpisodeControl wireControl(const EpisodeControl& control,
                                                   const std::string& run_id);

}  // namespace sensornet::emulator
