#pragma once
// The partitions of one run, beside the run's own partition P = "sensornet/<run_id>"
// (dds/domain.hpp), which carries every topic but these:
//
//   P/sensors/<ids>    Measurement, EpisodeTally and SensorStatus of the process that speaks for
//                      sensors <ids> (formatSensorIds: "3", "0-4", "0,2,5-7"); their readers
//                      join P/sensors/* and learn from the writer's partition whom it speaks for
//   P/launcher         Command of the launcher (the sensors' failure notices)
//   P/operator         Command of an operator (sensornet replan, status)
//
// In a secured run every identity's permissions (sensornet pki init) allow it to publish in its
// own partition only, and DDS Security refuses any other writer on both sides: the partition a
// sample came in then names the authenticated identity that wrote it, and the order in which
// writers appear decides nothing. Without security the partitions say the same, unauthenticated
// (the one-writer rule, writer_claims.hpp, still holds).
//
//   const std::string mine = sensorPartition("sensornet/demo", {0, 1, 2});  // ".../sensors/0-2"
//   sensorsOfPartition("sensornet/demo", mine)                              // {0, 1, 2}

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sensornet::emulator {

// The partition of the sensor topics a process speaking for `sensors` (sorted) writes in.
[[nodiscard]] std::string sensorPartition(std::string_view run_partition,
                                          const std::vector<int>& sensors);
// What a reader of the sensor topics joins: every sensor process's partition of the run.
[[nodiscard]] std::string sensorPartitionPattern(std::string_view run_partition);
// The sensors `partition` speaks for, or nullopt when it is not a sensor partition of this run
// in its canonical form (anything else, "P/sensors/0,1" for "P/sensors/0-1" included).
[[nodiscard]] std::optional<std::vector<int>> sensorsOfPartition(std::string_view run_partition,
                                                                 std::string_view partition);
// The same for a writer in several partitions: the sensors of the one sensor partition among
// them; nullopt when there is none or more than one (a writer speaks for one block).
[[nodiscard]] std::optional<std::vector<int>> sensorsOfPartitions(
    std::string_view run_partition, const std::vector<std::string>& partitions);

// Who sent a Command, as the partition it came in says (authenticated in a secured run).
enum class CommandSender { Launcher, Operator };
[[nodiscard]] std::string commandPartition(std::string_view run_partition, CommandSender sender);
[[nodiscard]] std::string_view commandSenderName(CommandSender sender) noexcept;
// Where a reference fusion center (ours beside an external one, `launch --reference-fusion`)
// writes its Report and FusionState: "P/reference", which the coordinator and the launcher's
// readers in P do not match, so that only the external fusion center paces the run.
[[nodiscard]] std::string referencePartition(std::string_view run_partition);
// How the coordinator's CommandReply begins when it refused a command its sender had no right
// to send (the fusion center records it as a command_refused fault).
inline constexpr std::string_view kNotPermitted = "not permitted: ";

}  // namespace sensornet::emulator
