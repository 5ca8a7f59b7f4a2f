#include "sensornet/recording/recording_replay.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <memory>
#include <variant>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/sample_fields.hpp"
#include "sensornet/emulator/fusion_center_core.hpp"
#include "sensornet/wire/fusion_center_events.hpp"
#include "sensornet/wire/run_inputs.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/utc_time.hpp"
#include "sensornet/report/report_files.hpp"

namespace sensornet::recording {

using namespace sensornet::emulator;  // the cores and their events
using namespace sensornet::wire;      // the samples' codecs

namespace {

using sensornet::report::EpisodeLog;
using sensornet::report::episodeLogPath;

using nlohmann::json;

// What the recording says of each writer: the partition it wrote in (its channel's metadata).
// Every recorded writer counts as live and matched: the recording holds what it sent.
class RecordedWriters final : public WriterFacts {
 public:
  explicit RecordedWriters(std::string run_partition) : run_(std::move(run_partition)) {}
  void add(WriterId writer, const std::string& partition, bool measurement) {
    const auto sensors = sensorsOfPartition(run_, partition);
    sensors_[writer] = sensors.value_or(std::vector<int>{});
    if (measurement) ++measurement_writers_;
  }
  [[nodiscard]] bool live(SensorTopic, WriterId) const override { return true; }
  [[nodiscard]] std::uint32_t matchedMeasurementWriters() const override {
    return measurement_writers_;
  }
  [[nodiscard]] bool writersMatchedWith(WriterId) const override { return true; }
  [[nodiscard]] const std::vector<int>& sensorsOf(SensorTopic, WriterId w) const override {
    static const std::vector<int> none;
    const auto it = sensors_.find(w);
    return it != sensors_.end() ? it->second : none;
  }

 private:
  std::string run_;
  std::map<WriterId, std::vector<int>> sensors_;
  std::uint32_t measurement_writers_ = 0;
};

}  // namespace

std::string recordedRunId(const McapReader& file, const std::string& source) {
  for (const auto& [name, values] : file.metadata()) {
    if (name == "run" && values.contains("run_id")) return values.at("run_id");
  }
  throw InputError(source, "metadata run.run_id",
                   "a recording of sensornet launch --record (its run metadata names the run)");
}

ReplayResult replayRecording(const McapReader& file, const std::string& source,
                             const std::filesystem::path& report_path) {
  ReplayResult result;
  result.run_id = recordedRunId(file, source);
  const std::string run = "sensornet/" + result.run_id;

  RecordedWriters writers(run);
  std::map<std::uint16_t, const dds::SampleType*> types;
  std::map<std::uint16_t, std::string> partitions;
  for (const auto& [id, channel] : file.channels()) {
    const dds::SampleType* type = dds::sampleTypeOfTopic(channel.topic);
    if (type == nullptr || channel.message_encoding != "cdr") continue;  // not ours: skipped
    types[id] = type;
    const auto p = channel.metadata.find("partition");
    partitions[id] = p != channel.metadata.end() ? p->second : "";
    writers.add(id + 1U, partitions[id], channel.topic == "sensornet/Measurement");
  }

  FusionCenterConfig config;
  config.run_id = result.run_id;
  config.episode_log = true;
  config.episode_log_path = episodeLogPath(report_path).string();
  const std::int64_t first_ns =
      file.messages().empty() ? 0 : static_cast<std::int64_t>(file.messages().front().log_time_ns);
  FusionCenterCore core(config, writers, first_ns);
  RunInputState inputs;
  EpisodeLog log(episodeLogPath(report_path));
  std::map<std::uint32_t, ReplayedEpisode> episodes;
  std::optional<RunEnd> end;
  std::vector<std::pair<std::size_t, std::int64_t>> held;  // tallies before the scenario

  const auto carryOut = [&] {
    for (FusionAction& action : core.takeActions()) {
      if (const auto* entry = std::get_if<AppendEpisodeLog>(&action)) {
        log.append(entry->entry);
        const auto k = entry->entry.at("episode").get<std::uint32_t>();
        ReplayedEpisode& e = episodes[k];
        e.episode = k;
        const json& cost = entry->entry.at("realized_cost");
        if (cost.is_number()) e.replayed_cost = cost.get<double>();
        e.complete = entry->entry.value("complete", false);
      } else if (const auto* line = std::get_if<LogLine>(&action)) {
        if (line->level >= spdlog::level::warn) spdlog::log(line->level, "replay: {}", line->text);
      } else if (const auto* final_report = std::get_if<WriteFinalReport>(&action)) {
        writeJsonFile(report_path.string(), "replay report", [&](std::ostream& out) {
          core.report().write(out, final_report->doc, 2);
          out << '\n';
        });
      }
    }
  };
  const auto follow = [&](RunInputState::Update& update, std::int64_t now) {
    inputs.releaseStarts(update);
    if (auto run_end = feedInputs(core, inputs, update, now)) end = std::move(run_end);
  };

  std::vector<std::size_t> held_schedules;  // schedules before the scenario, by message index
  const auto handle = [&](std::size_t index, std::int64_t now) {
    const McapMessage& m = file.messages()[index];
    const auto type = types.find(m.channel_id);
    if (type == types.end()) return;
    const std::string where = source + ", message " + std::to_string(index);
    const dds::DecodedSample sample(*type->second, m.data, where);
    const WriterId writer = m.channel_id + 1U;
    const std::string topic = type->second->topic;
    RunInputState::Update update;
    if (topic == "sensornet/Scenario") {
      wire::feedSample(inputs, sample.as<sensornet_Scenario>(), update);
      follow(update, now);
    } else if (topic == "sensornet/Schedule") {
      if (!inputs.hasScenario()) {
        held_schedules.push_back(index);
        return;
      }
      wire::feedSample(inputs, sample.as<sensornet_Schedule>(), update);
      follow(update, now);
    } else if (topic == "sensornet/EpisodeControl") {
      wire::feedSample(inputs, sample.as<sensornet_EpisodeControl>(), update);
      follow(update, now);
    } else if (topic == "sensornet/Measurement") {
      core.onMeasurement(
          arrivalOfSample(sample.as<sensornet_Measurement>(), now, writer, config.run_id), now);
      ++result.samples_fused;
    } else if (topic == "sensornet/EpisodeTally") {
      if (!core.hasScenario()) {
        held.emplace_back(index, now);
        return;
      }
      core.onTally(tallyOfSample(sample.as<sensornet_EpisodeTally>(), writer), now);
    } else if (topic == "sensornet/SensorStatus") {
      core.onStatus(statusOfSample(sample.as<sensornet_SensorStatus>(), writer), now);
    } else if (topic == "sensornet/CommandReply") {
      const auto& reply = sample.as<sensornet_CommandReply>();
      if (const auto why = refusalByRight(reply, result.run_id)) {
        core.onCommandRefused(reply.command_id, *why, now);
      }
    } else if (topic == "sensornet/Report" && partitions[m.channel_id] == run) {
      const auto& r = sample.as<sensornet_Report>();  // what the recorded run published
      ReplayedEpisode& e = episodes[r.episode];
      e.episode = r.episode;
      if (!e.recorded_cost) e.recorded_cost = r.realized_cost;
    }
  };

  // The live fusion center's loop wakes at least every 10 ms; so do its ticks here, in recorded
  // time, or the gaps between samples would look like stalls of its own.
  constexpr std::int64_t kTickNs = 10'000'000;
  std::int64_t now = first_ns, ticked = first_ns;
  for (std::size_t i = 0; i < file.messages().size(); ++i) {
    now = static_cast<std::int64_t>(file.messages()[i].log_time_ns);
    for (; ticked + kTickNs < now; ticked += kTickNs) {
      core.tick(ticked + kTickNs);
      carryOut();
    }
    const bool had_scenario = inputs.hasScenario();
    handle(i, now);
    if (!had_scenario && inputs.hasScenario()) {  // what waited for it, in recorded order
      for (const std::size_t s : std::exchange(held_schedules, {})) handle(s, now);
    }
    if (core.hasScenario() && !held.empty()) {
      for (const auto& [t, at] : std::exchange(held, {})) handle(t, now);
    }
    core.tick(now);
    carryOut();
    ++result.samples_read;
  }
  result.status = core.finish(end, inputs.rejected(), utcNow(), now);
  carryOut();
  for (auto& [k, e] : episodes) result.episodes.push_back(e);
  return result;
}

}  // namespace sensornet::recording
