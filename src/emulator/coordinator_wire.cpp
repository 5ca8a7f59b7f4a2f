#include "sensornet/emulator/coordinator_wire.hpp"

#include "sensornet/dds/wire.hpp"

namespace sensornet::emulator {

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

sensornet_EpisodeCommand episodeCommandOf(ControlKind kind) {
  switch (kind) {
    case ControlKind::EpisodeStart:
      return sensornet_EPISODE_START;
    case ControlKind::SensorsFailed:
      return sensornet_EPISODE_SENSORS_FAILED;
    case ControlKind::RunShutdown:
      return sensornet_RUN_SHUTDOWN;
  }
  return sensornet_RUN_SHUTDOWN;
}

sensornet_EpisodeControl wireControl(const EpisodeControl& control, const std::string& run_id) {
  sensornet_EpisodeControl c{};
  c.run_id = dds::borrowString(run_id);
  c.episode = control.episode;
  c.command = episodeCommandOf(control.kind);
  c.start_wall_time_ns = control.start_wall_ns;
  c.time_scale = control.time_scale;
  c.seed = control.seed;
  c.schedule_version = control.schedule_version;
  c.episodes_planned = control.episodes_planned;
  c.failed_at_s = control.failed_at_s;
  c.aborted = control.aborted;
  c.detail = dds::borrowString(control.detail);
  dds::borrowSequence(c.failed_sensors, control.failed_sensors);
  return c;
}

}  // namespace sensornet::emulator
