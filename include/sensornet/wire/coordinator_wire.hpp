#pragma once
// The coordinator core's events from their DDS samples, and its episode controls as samples
// (idl/sensornet.idl): what `coordinator serve` reads and writes, field by field, without the
// loop that carries them.
//
//   core.onCommand(commandOf(*received.sample, CommandSender::Launcher), now);
//   core.onReport(reportOf(*received.sample), now);
//   writer.write(wireControl(action.control, run_id));   // borrows from both: keep them alive
//   reply_writer.write(wireReply(run_id, action.command_id, action.answer));   // borrows too
//   FusionCenterPresence presence(control_writer, report_reader, state_reader);
//   core.onFusionCenterMatched(presence.present(now));
//   CoordinatorEndpoints dds(run.domainConfig());       // every endpoint of `coordinator serve`

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/coordinator_core.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/sensor_speakers.hpp"

namespace sensornet::wire {

// Unknown for a kind this program does not know (a newer sender's).
[[nodiscard]] emulator::CommandKind commandKindOf(sensornet_CommandKind kind);
[[nodiscard]] emulator::CommandEvent commandOf(const sensornet_Command& c,
                                               emulator::CommandSender sender);
[[nodiscard]] emulator::ReportEvent reportOf(const sensornet_Report& r);
// A sensor's status; `speaks(sensor)` tells whether its writer may speak for that sensor.
// nullopt (and a warning in the log) for a state this program does not know.
[[nodiscard]] std::optional<emulator::SensorStatusEvent> sensorStatusOf(
    const sensornet_SensorStatus& s, const std::function<bool(int)>& speaks);
[[nodiscard]] emulator::FusionStateEvent fusionStateOf(const sensornet_FusionState& s);
// The episode controls' codec is messages.hpp's (wireControl, controlOf).

// The reply to command `command_id` as its sample; it borrows `run_id` and `answer`'s reason.
[[nodiscard]] sensornet_CommandReply wireReply(const std::string& run_id,
                                               std::uint64_t command_id,
                                               const emulator::AnsweredCommand& answer);

// The fusion center counts as present once one participant matched all three: a reader of the
// coordinator's EpisodeControl writer, and writers of its Report and FusionState readers.
// Discovery announces endpoints one by one (on a lossy link seconds apart), and a control reader
// that matches after the first two episodes were announced gets only the latest of them. The
// participants are looked up again when a match count changes, and twice a second in case one
// endpoint left and another came between two looks.
class FusionCenterPresence {
 public:
  FusionCenterPresence(const dds::detail::WriterCore& control_writer,
                       const dds::detail::ReaderCore& report_reader,
                       const dds::detail::ReaderCore& state_reader)
      : control_(control_writer), report_(report_reader), state_(state_reader) {}
  [[nodiscard]] bool present(std::int64_t now_ns);

 private:
  const dds::detail::WriterCore& control_;
  const dds::detail::ReaderCore& report_;
  const dds::detail::ReaderCore& state_;
  std::array<std::uint32_t, 3> counts_{};
  std::int64_t recheck_ns_ = 0;
  bool present_ = false;
};

// Waits until every participant that reads EpisodeControl (`control_writer`'s readers) reads
// the Scenario too (`scenario_writer`'s), or `limit` passed.
void awaitScenarioReaders(const dds::detail::WriterCore& scenario_writer,
                          const dds::detail::WriterCore& control_writer,
                          std::chrono::milliseconds limit);

// The DDS entities of `coordinator serve`, each topic with its QoS and partition: it writes the
// Scenario, the Schedule versions, the EpisodeControls and the CommandReplies; reads Commands in
// two partitions (by right, run_partitions.hpp: the partition a Command came in names who sent
// it, and in a secured run only the launcher may write in the launcher's), the SensorStatuses
// of every sensor's partition (with who may speak for each sensor), the Reports and the
// FusionState. The waitset wakes on commands, statuses and reports.
struct CoordinatorEndpoints {
  explicit CoordinatorEndpoints(const dds::DomainConfig& config);
  CoordinatorEndpoints(const CoordinatorEndpoints&) = delete;
  CoordinatorEndpoints& operator=(const CoordinatorEndpoints&) = delete;

  dds::Domain domain;
  dds::Participant participant;
  dds::Topic<sensornet_Scenario> scenario_topic{participant};
  dds::Topic<sensornet_Schedule> schedule_topic{participant};
  dds::Topic<sensornet_EpisodeControl> control_topic{participant};
  dds::Topic<sensornet_Command> command_topic{participant};
  dds::Topic<sensornet_CommandReply> reply_topic{participant};
  dds::Topic<sensornet_SensorStatus> status_topic{participant};
  dds::Topic<sensornet_Report> report_topic{participant};
  dds::Topic<sensornet_FusionState> state_topic{participant};
  dds::Writer<sensornet_Scenario> scenario_writer{participant, scenario_topic};
  dds::Writer<sensornet_Schedule> schedule_writer{participant, schedule_topic};
  dds::Writer<sensornet_EpisodeControl> control_writer{participant, control_topic};
  dds::Writer<sensornet_CommandReply> reply_writer{participant, reply_topic};
  dds::Reader<sensornet_Command> launcher_commands;
  dds::Reader<sensornet_Command> operator_commands;
  dds::Reader<sensornet_SensorStatus> status_reader;
  SensorSpeakers speakers;
  dds::Reader<sensornet_Report> report_reader{participant, report_topic};
  dds::Reader<sensornet_FusionState> state_reader{participant, state_topic};
  dds::WaitSet waitset{participant};
  dds::ReadCondition launcher_command_ready{launcher_commands};
  dds::ReadCondition operator_command_ready{operator_commands};
  dds::ReadCondition status_ready{status_reader};
  dds::ReadCondition report_ready{report_reader};
  FusionCenterPresence presence{control_writer, report_reader, state_reader};
};

}  // namespace sensornet::wire
