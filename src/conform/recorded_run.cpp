// A run's recording read for the conformance rules: the run's inputs as a process keeps them,
// the episodes' starts and the shutdown, and each asked-for sensor's samples, tallies and
// statuses, taken only from writers whose partition names that sensor (a sample of another
// writer is not the participant's).
#include <algorithm>

#include "sensornet/conform/sensor_conformance.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/sample_fields.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/recording/recording_replay.hpp"
#include "sensornet/wire/coordinator_wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_inputs.hpp"

namespace sensornet::conform {
namespace {

// The IDL's name of an enum value of `field` ("COMMAND_REPLAN"), or the number.
std::string enumName(const dds::SampleType& type, std::string_view field, int value) {
  for (const dds::SampleField& f : type.fields) {
    if (f.name != field || f.enum_names == nullptr) continue;
    for (const dds::EnumName& e : *f.enum_names) {
      if (e.value == value) return e.name;
    }
  }
  return std::to_string(value);
}

}  // namespace

RecordedRun readRecording(const McapReader& file, const std::string& source,
                          const std::vector<int>& sensors) {
  RecordedRun run;
  run.run_id = recording::recordedRunId(file, source);
  const std::string partition = "sensornet/" + run.run_id;
  for (const int j : sensors) run.sensors[j];
  if (!file.messages().empty()) {
    run.first_ns = static_cast<std::int64_t>(file.messages().front().log_time_ns);
  }

  // Per channel: its type, and the one sensor its writer speaks for (-1: none of those asked).
  struct Channel {
    const dds::SampleType* type = nullptr;
    std::string partition;  // its writer's
    int sensor = -1;
    std::vector<RecordedReport>* report = nullptr;  // a Report channel of the run or reference
  };
  std::map<std::uint16_t, Channel> channels;
  for (const auto& [id, channel] : file.channels()) {
    const dds::SampleType* type = dds::sampleTypeOfTopic(channel.topic);
    if (type == nullptr || channel.message_encoding != "cdr") continue;
    Channel c{type, "", -1, nullptr};
    const auto p = channel.metadata.find("partition");
    if (p != channel.metadata.end()) c.partition = p->second;
    if (p != channel.metadata.end() && channel.topic == "sensornet/Report") {
      if (p->second == partition) c.report = &run.reports;
      if (p->second == emulator::referencePartition(partition)) c.report = &run.reference_reports;
    } else if (p != channel.metadata.end()) {
      const auto named = emulator::sensorsOfPartition(partition, p->second);
      if (named && named->size() == 1 && run.sensors.contains(named->front())) {
        c.sensor = named->front();
      }
    }
    channels[id] = c;
  }

  std::vector<std::size_t> held_schedules;  // before the scenario, in recorded order
  emulator::RunInputState::Update ignored;
  const auto take = [&](std::size_t index) {
    const McapMessage& m = file.messages()[index];
    const auto found = channels.find(m.channel_id);
    if (found == channels.end()) return;
    const Channel& channel = found->second;
    const std::string where = source + ", message " + std::to_string(index);
    const dds::DecodedSample sample(*channel.type, m.data, where);
    const std::string topic = channel.type->topic;
    const auto at = static_cast<std::int64_t>(m.log_time_ns);
    const auto written = static_cast<std::int64_t>(m.publish_time_ns);
    if (topic == "sensornet/Scenario") {
      wire::feedSample(run.inputs, sample.as<sensornet_Scenario>(), ignored);
    } else if (topic == "sensornet/Schedule") {
      if (!run.inputs.hasScenario()) {
        held_schedules.push_back(index);
        return;
      }
      wire::feedSample(run.inputs, sample.as<sensornet_Schedule>(), ignored);
    } else if (topic == "sensornet/EpisodeControl") {
      const emulator::EpisodeControl control =
          wire::controlOf(sample.as<sensornet_EpisodeControl>());
      if (control.kind == emulator::ControlKind::EpisodeStart) {
        run.starts_ns.emplace(control.episode, control.start_wall_ns);
        run.time_scale = control.time_scale;
      } else if (control.kind == emulator::ControlKind::RunShutdown && !run.shutdown_ns) {
        run.shutdown_ns = at;
        run.shutdown_written_ns = written;
      }
    } else if (topic == "sensornet/Report" && channel.report != nullptr) {
      const auto& s = sample.as<sensornet_Report>();
      RecordedReport report{
          s.episode, s.realized_cost, s.bracket_lower, s.bracket_upper, s.nees, s.complete, {}, at};
      for (std::uint32_t i = 0; i < s.counts._length; ++i) {
        const sensornet_SensorCounts& c = s.counts._buffer[i];
        if (c.sensor_id >= report.counts.size()) report.counts.resize(c.sensor_id + 1);
        report.counts[c.sensor_id] = {c.sent, c.received, c.lost};
      }
      channel.report->push_back(std::move(report));
    } else if (topic == "sensornet/Command") {
      const auto& s = sample.as<sensornet_Command>();
      run.commands.push_back({wire::commandOf(s, emulator::CommandSender::Operator),
                              enumName(*channel.type, "kind", s.kind), channel.partition,
                              written});
    } else if (topic == "sensornet/CommandReply") {
      const auto& s = sample.as<sensornet_CommandReply>();
      if (dds::viewString(s.run_id) != run.run_id) return;
      run.replies.push_back({s.command_id, s.accepted, s.schedule_version,
                             std::string(dds::viewString(s.reason)), written});
    } else if (channel.sensor >= 0) {
      SensorTrace& trace = run.sensors[channel.sensor];
      if (topic == "sensornet/Measurement") {
        const auto& s = sample.as<sensornet_Measurement>();
        if (static_cast<int>(s.sensor_id) != channel.sensor) return;
        trace.samples.push_back({s.episode, s.seq, s.emulated_time_s, s.schedule_version,
                                 std::vector<double>(s.z._buffer, s.z._buffer + s.z._length), at});
      } else if (topic == "sensornet/EpisodeTally") {
        const auto& s = sample.as<sensornet_EpisodeTally>();
        if (static_cast<int>(s.sensor_id) != channel.sensor) return;
        trace.tallies.push_back({s.episode, s.sent, s.finished, at});
      } else if (topic == "sensornet/SensorStatus") {
        const auto& s = sample.as<sensornet_SensorStatus>();
        const auto state = wire::sensorStateOf(s.state);
        if (static_cast<int>(s.sensor_id) != channel.sensor || !state) return;
        trace.statuses.push_back({*state, s.schedule_version, at, written});
      }
    }
  };
  for (std::size_t i = 0; i < file.messages().size(); ++i) {
    const bool had_scenario = run.inputs.hasScenario();
    take(i);
    if (!had_scenario && run.inputs.hasScenario()) {
      for (const std::size_t s : std::exchange(held_schedules, {})) take(s);
    }
  }
  if (!run.inputs.hasScenario()) {
    throw InputError(source, "sensornet/Scenario",
                     "a recording that holds the run's Scenario (sensornet launch --record)");
  }
  return run;
}

}  // namespace sensornet::conform
