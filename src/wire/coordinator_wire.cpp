#include "sensornet/wire/coordinator_wire.hpp"

#include "sensornet/dds/wire.hpp"

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

}  // namespace sensornet::wire
