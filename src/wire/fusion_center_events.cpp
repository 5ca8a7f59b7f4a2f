#include "sensornet/wire/fusion_center_events.hpp"

#include <Eigen/Core>
#include <string_view>

#include "sensornet/dds/wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/emulator/run_partitions.hpp"

namespace sensornet::wire {

using namespace sensornet::emulator;  // the core events this file decodes


// Touches nothing but the sample: safe in Cyclone's receive thread.
MeasurementArrival arrivalOfSample(const sensornet_Measurement& m, std::int64_t received_ns,
                                   WriterId writer, std::string_view own_run) {
  MeasurementArrival a;
  FusedMeasurement& fused = a.measurement;
  fused.sensor = static_cast<int>(m.sensor_id);
  fused.seq = m.seq;
  fused.time_s = m.emulated_time_s;
  fused.version = m.schedule_version;
  const auto z = dds::viewSequence(m.z);
  fused.z = Eigen::Map<const Eigen::VectorXd>(z.data(), static_cast<Eigen::Index>(z.size()));
  fused.publish_wall_ns = m.publish_wall_time_ns;
  fused.receive_wall_ns = received_ns;
  fused.network_delay_s = m.network_delay_s;
  a.episode = m.episode;
  if (const std::string_view run = dds::viewString(m.run_id); run != own_run) {
    a.other_run = std::string(run);
  }
  a.writer = writer;
  return a;
}

EpisodeTally tallyOfSample(const sensornet_EpisodeTally& t, WriterId writer) {
  EpisodeTally out;
  out.sensor = t.sensor_id;
  out.run_id = std::string(dds::viewString(t.run_id));
  out.episode = t.episode;
  out.count = {t.sent, t.dropped_by_network, t.duplicated_by_network};
  out.max_lag_s = t.max_lag_s;
  out.stalled_s = t.stalled_s;
  out.wall_time_ns = t.wall_time_ns;
  out.writer = writer;
  return out;
}

SensorStatus statusOfSample(const sensornet_SensorStatus& s, WriterId writer) {
  SensorStatus out;
  out.sensor = s.sensor_id;
  out.run_id = std::string(dds::viewString(s.run_id));
  out.episode = s.episode;
  // A state word this build does not know (a newer peer's) reads as starting: no decision
  // rests on it.
  out.state = sensorStateOf(s.state).value_or(SensorState::Starting);
  out.sent_in_episode = s.sent_in_episode;
  out.process_id = s.process_id;
  out.wall_time_ns = s.wall_time_ns;
  out.writer = writer;
  return out;
}

std::optional<std::string> refusalByRight(const sensornet_CommandReply& r, const std::string& run_id) {
  const std::string_view reason = dds::viewString(r.reason);
  if (r.accepted || dds::viewString(r.run_id) != run_id ||
      reason.substr(0, kNotPermitted.size()) != kNotPermitted) {
    return std::nullopt;
  }
  return std::string(reason.substr(kNotPermitted.size()));
}

std::optional<RunEnd> feedInputs(FusionCenterCore& core, const RunInputState& inputs,
                                 const RunInputState::Update& update, std::int64_t now) {
  if (update.scenario_arrived) {
    const RunScenario& run = inputs.run();
    core.onScenario({run.scenario, run.digest, run.seed}, now);
  }
  if (update.new_versions > 0) {
    const auto& versions = inputs.book().versions();
    core.onScheduleVersions(
        {versions.end() - static_cast<std::ptrdiff_t>(update.new_versions), versions.end()}, now);
  }
  for (const EpisodeStart& start : update.starts) core.onEpisodeStart(start, now);
  for (const SensorFailure& failure : update.failures) core.onSensorFailure(failure, now);
  if (update.shutdown) return update.end;
  return std::nullopt;
}

}  // namespace sensornet::wire
