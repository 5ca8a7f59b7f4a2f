#include "sensornet/wire/coordinator_wire.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <thread>

#include "sensornet/dds/matched_endpoints.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/emulator/run_partitions.hpp"

namespace sensornet::wire {

using namespace sensornet::emulator;  // the core types this file encodes and decodes


CommandKind commandKindOf(sensornet_CommandKind kind) {
  using K = CommandKind;
  switch (kind) {
    case sensornet_COMMAND_REPLAN:
      return K::Replan;
    case sensornet_COMMAND_EXCLUDE_SENSORS:
      return K::ExcludeSensors;
    case sensornet_COMMAND_SET_BUDGET:
      return K::SetBudget;
    case sensornet_COMMAND_SCHEDULE_FILE:
      return K::ScheduleFile;
    case sensornet_COMMAND_STATUS:
      return K::Status;
    case sensornet_COMMAND_SHUTDOWN:
      return K::Shutdown;
    case sensornet_COMMAND_SENSORS_FAILED:
      return K::SensorsFailed;
    case sensornet_COMMAND_INCLUDE_SENSORS:
      return K::IncludeSensors;
  }
  return K::Unknown;
}

CommandEvent commandOf(const sensornet_Command& c, CommandSender sender) {
  CommandEvent e;
  e.sender = sender;
  e.run_id = std::string(dds::viewString(c.run_id));
  e.command_id = c.command_id;
  e.kind = commandKindOf(c.kind);
  e.issuer = std::string(dds::viewString(c.issuer));
  e.surrogate = std::string(dds::viewString(c.surrogate));
  const auto ids = dds::viewSequence(c.sensor_ids);
  e.sensor_ids.assign(ids.begin(), ids.end());
  const auto budget = dds::viewSequence(c.budget);
  e.budget.assign(budget.begin(), budget.end());
  e.schedule_json = std::string(dds::viewString(c.schedule_json));
  e.detail = std::string(dds::viewString(c.detail));
  return e;
}

ReportEvent reportOf(const sensornet_Report& r) {
  return {r.episode,
          r.realized_cost,
          r.bracket_lower,
          r.bracket_upper,
          r.summary.episodes,
          r.summary.realized_mean,
          r.summary.realized_ci95_low,
          r.summary.realized_ci95_high};
}

FusionStateEvent fusionStateOf(const sensornet_FusionState& s) {
  const auto values = dds::viewSequence(s.covariance);
  return {s.episode, s.emulated_time_s, s.state_dim, {values.begin(), values.end()}};
}

std::optional<emulator::SensorStatusEvent> sensorStatusOf(
    const sensornet_SensorStatus& s, const std::function<bool(int)>& speaks) {
  const auto state = sensorStateOf(s.state);
  if (!state) {
    spdlog::warn("ignored a status of sensor {} with state {}", s.sensor_id,
                 static_cast<int>(s.state));
    return std::nullopt;
  }
  const int sensor = static_cast<int>(s.sensor_id);
  return emulator::SensorStatusEvent{sensor, *state, s.schedule_version,
                                     std::string(dds::viewString(s.detail)), speaks(sensor)};
}

sensornet_CommandReply wireReply(const std::string& run_id, std::uint64_t command_id,
                                 const emulator::AnsweredCommand& answer) {
  sensornet_CommandReply reply{};
  reply.run_id = dds::borrowString(run_id);
  reply.command_id = command_id;
  reply.accepted = answer.accepted;
  reply.schedule_version = answer.schedule_version;
  reply.reason = dds::borrowString(answer.reason);
  return reply;
}

bool FusionCenterPresence::present(std::int64_t now_ns) {
  const std::array<std::uint32_t, 3> counts{control_.matchedReaders(), report_.matchedWriters(),
                                            state_.matchedWriters()};
  if (counts != counts_ || now_ns >= recheck_ns_) {
    counts_ = counts;
    recheck_ns_ = now_ns + 500'000'000;
    present_ = counts[1] > 0 && counts[2] > 0 &&
               dds::sharesParticipant({dds::participantsOfMatchedReaders(control_),
                                       dds::participantsOfMatchedWriters(report_),
                                       dds::participantsOfMatchedWriters(state_)});
  }
  return present_;
}

void awaitScenarioReaders(const dds::detail::WriterCore& scenario_writer,
                          const dds::detail::WriterCore& control_writer,
                          std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  const auto missing = [&] {
    const auto scenario = dds::participantsOfMatchedReaders(scenario_writer);
    for (const dds::ParticipantKey& p : dds::participantsOfMatchedReaders(control_writer)) {
      if (std::find(scenario.begin(), scenario.end(), p) == scenario.end()) return true;
    }
    return false;
  };
  while (missing() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

CoordinatorEndpoints::CoordinatorEndpoints(const dds::DomainConfig& config)
    : domain(config),
      participant(domain),
      launcher_commands(participant, command_topic,
                        dds::endpointQosIn<sensornet_Command>(emulator::commandPartition(
                            participant.partition(), emulator::CommandSender::Launcher))),
      operator_commands(participant, command_topic,
                        dds::endpointQosIn<sensornet_Command>(emulator::commandPartition(
                            participant.partition(), emulator::CommandSender::Operator))),
      status_reader(participant, status_topic,
                    dds::readerQosMatching<sensornet_SensorStatus>(
                        emulator::sensorPartitionPattern(participant.partition()))),
      speakers(participant.partition()) {
  waitset.attach(launcher_command_ready, 1);
  waitset.attach(status_ready, 2);
  waitset.attach(report_ready, 3);
  waitset.attach(operator_command_ready, 4);
}

}  // namespace sensornet::wire
