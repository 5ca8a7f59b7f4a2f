#include "replay_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "sensornet/io/output_file.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/recording/live_replay.hpp"
#include "sensornet/recording/recording_replay.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/io/mcap.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/io/utc_time.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;

struct ReplayOptions {
  std::string path;
  bool info = false;
  bool json = false;
  std::string report;  // the replay's report; default beside the recording: RUN.replay.json
  bool live = false;   // republish into a new run instead of fusing here
  wire::RunOptions run;  // --live: the new run
  double time_scale = 1.0;
  double ready_timeout_s = 30.0;
};

int runLive(const ReplayOptions& options) {
  if (options.run.run_id.empty()) {
    throw InputError("sensornet replay --live", "--run-id", "the new run's id (a fresh one)");
  }
  const McapReader file(options.path);
  std::fprintf(stderr,
               "sensornet: republishing %s as run %s at %gx the recorded pace; start its fusion "
               "center now (fusion_center serve --run-id %s, or your own)\n",
               options.path.c_str(), options.run.run_id.c_str(), options.time_scale,
               options.run.run_id.c_str());
  const recording::LiveReplayResult r =
      recording::replayLive(file, options.path, options.run, options.time_scale,
                           options.ready_timeout_s);
  std::printf("run %s replayed live from %s: %llu samples in %.2f s\n", options.run.run_id.c_str(),
              options.path.c_str(), static_cast<unsigned long long>(r.written), r.wall_s);
  return kExitOk;
}

std::string utcOf(std::uint64_t ns) {
  const std::chrono::nanoseconds since_epoch(static_cast<std::int64_t>(ns));
  return utcText(std::chrono::system_clock::time_point(
                     std::chrono::duration_cast<std::chrono::system_clock::duration>(since_epoch)),
                 UtcForm::Milliseconds);
}

int runInfo(const ReplayOptions& options) {
  const McapReader file(options.path);
  std::map<std::uint16_t, std::uint64_t> counted;
  std::uint64_t first = 0, last = 0;
  for (const McapMessage& m : file.messages()) {
    ++counted[m.channel_id];
    first = counted.size() == 1 && counted.begin()->second == 1 ? m.log_time_ns
                                                                  : std::min(first, m.log_time_ns);
    last = std::max(last, m.log_time_ns);
  }
  // The summary says what the messages are: a mismatch means the file is not what it claims.
  if (const auto& stats = file.statistics()) {
    if (stats->message_count != file.messages().size()) {
      throw InputError(options.path, "statistics.message_count",
                       std::to_string(file.messages().size()) + " (the messages in the file), got " +
                           std::to_string(stats->message_count));
    }
  }
  nlohmann::json channels = nlohmann::json::array();
  for (const auto& [id, channel] : file.channels()) {
    const auto schema = file.schemas().find(channel.schema_id);
    channels.push_back({{"id", id},
                        {"topic", channel.topic},
                        {"partition", channel.metadata.contains("partition")
                                          ? channel.metadata.at("partition")
                                          : ""},
                        {"message_encoding", channel.message_encoding},
                        {"schema", schema != file.schemas().end() ? schema->second.name : ""},
                        {"schema_encoding",
                         schema != file.schemas().end() ? schema->second.encoding : ""},
                        {"messages", counted.contains(id) ? counted.at(id) : 0}});
  }
  nlohmann::json metadata = nlohmann::json::object();
  for (const auto& [name, values] : file.metadata()) metadata[name] = values;
  const bool any = !file.messages().empty();
  if (options.json) {
    std::printf("%s\n", nlohmann::json({{"file", options.path},
                                        {"profile", file.profile()},
                                        {"messages", file.messages().size()},
                                        {"chunks", file.chunkCount()},
                                        {"start_ns", any ? nlohmann::json(first) : nullptr},
                                        {"end_ns", any ? nlohmann::json(last) : nullptr},
                                        {"channels", channels},
                                        {"metadata", metadata}})
                            .dump()
                            .c_str());
    return kExitOk;
  }
  std::printf("file:     %s\nprofile:  %s\nmessages: %zu in %u chunks\n", options.path.c_str(),
              file.profile().c_str(), file.messages().size(), file.chunkCount());
  if (any) {
    std::printf("start:    %s\nend:      %s\nduration: %.3f s\n", utcOf(first).c_str(),
                utcOf(last).c_str(), 1e-9 * static_cast<double>(last - first));
  }
  for (const auto& [name, values] : file.metadata()) {
    std::printf("metadata %s:", name.c_str());
    for (const auto& [key, value] : values) std::printf(" %s=%s", key.c_str(), value.c_str());
    std::printf("\n");
  }
  std::printf("channels:\n");
  for (const nlohmann::json& c : channels) {
    std::printf("  (%d) %-24s %-34s %8llu msgs  %s [%s/%s]\n", c.at("id").get<int>(),
                c.at("topic").get<std::string>().c_str(),
                c.at("partition").get<std::string>().c_str(),
                static_cast<unsigned long long>(c.at("messages").get<std::uint64_t>()),
                c.at("schema").get<std::string>().c_str(),
                c.at("message_encoding").get<std::string>().c_str(),
                c.at("schema_encoding").get<std::string>().c_str());
  }
  return kExitOk;
}

std::string costText(const std::optional<double>& cost) {
  if (!cost) return "-";
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", *cost);
  return text;
}

// Re-fuses the recording offline and compares each episode's cost with the recorded run's.
int runOffline(const ReplayOptions& options) {
  const McapReader file(options.path);
  fs::path report = options.report;
  if (report.empty()) report = fs::path(options.path).replace_extension(".replay.json");
  makeParentFolders(report, "--report");
  checkOutputFile(report, "--report");
  spdlog::set_level(spdlog::level::warn);  // the fusion center's progress lines are the live run's
  const recording::ReplayResult r = recording::replayRecording(file, options.path, report);
  std::size_t compared = 0, equal = 0;
  nlohmann::json episodes = nlohmann::json::array();
  for (const recording::ReplayedEpisode& e : r.episodes) {
    const bool both = e.replayed_cost && e.recorded_cost;
    const bool same = both && *e.replayed_cost == *e.recorded_cost;  // to the bit
    compared += both ? 1 : 0;
    equal += same ? 1 : 0;
    episodes.push_back({{"episode", e.episode},
                        {"replayed_cost", e.replayed_cost ? nlohmann::json(*e.replayed_cost) : nullptr},
                        {"recorded_cost", e.recorded_cost ? nlohmann::json(*e.recorded_cost) : nullptr},
                        {"complete", e.complete},
                        {"equal", same}});
    if (!options.json) {
      std::printf("episode %u: replayed %s, recorded %s%s\n", e.episode,
                  costText(e.replayed_cost).c_str(), costText(e.recorded_cost).c_str(),
                  !both ? "" : same ? " (equal)" : " (DIFFERENT)");
    }
  }
  const bool reproduced = compared == r.episodes.size() && equal == compared && compared > 0;
  if (options.json) {
    std::printf("%s\n", nlohmann::json({{"recording", options.path},
                                         {"run_id", r.run_id},
                                         {"status", std::string(wordOf(r.status))},
                                         {"report", report.string()},
                                         {"measurements_fused", r.samples_fused},
                                         {"episodes", episodes},
                                         {"reproduced", reproduced}})
                             .dump()
                             .c_str());
  } else {
    std::printf("run %s replayed from %s: %s, %llu measurements fused; %zu of %zu episodes "
                "equal the recording to the bit\nreport: %s\n",
                r.run_id.c_str(), options.path.c_str(), std::string(wordOf(r.status)).c_str(),
                static_cast<unsigned long long>(r.samples_fused), equal, r.episodes.size(),
                report.c_str());
  }
  // The replay says whether it reproduced the recording: any episode off, or without both
  // costs, is exit 1.
  return reproduced ? kExitOk : kExitFailure;
}

}  // namespace

Subcommand addReplayCommand(CLI::App& app) {
  auto options = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Re-fuse a recording of a run (sensornet launch --record RUN.mcap) offline: its samples "
      "in recorded order, at their recorded receipt times, through the fusion center's own "
      "decisions; prints per episode the replayed realized cost beside the recorded run's and "
      "writes the replay's report (default RUN.replay.json). Exit 0 when every episode equals "
      "the recording to the bit, 1 when one does not, 2 on a bad file. With --info: what the "
      "recording holds, like `mcap info`. With --live --run-id NEW: republish it into a new run "
      "at the recorded pace, for that run's fusion center (ours or yours). Examples:\n  "
      "sensornet replay run.mcap\n  sensornet replay run.mcap --info\n  sensornet replay "
      "run.mcap --live --run-id again --time-scale 2");
  cmd->add_option("RECORDING", options->path, "an MCAP file of sensornet launch --record")
      ->required();
  cmd->add_flag("--info", options->info, "print what the recording holds");
  cmd->add_option("--report", options->report,
                  "write the replay's report here (default: beside the recording, RUN.replay.json)");
  cmd->add_flag("--json", options->json, "one JSON line instead of the text");
  cmd->add_flag("--live", options->live,
                "republish the recorded run's own traffic (scenario, schedules, episode controls, "
                "every sensor's measurements, tallies and statuses) into the new run --run-id at "
                "the recorded timing, for a fusion center of that run (ours or yours) to fuse");
  wire::addRunOptions(*cmd, options->run, false);
  cmd->add_option("--time-scale", options->time_scale,
                  "with --live: how much faster than recorded (2: twice as fast)")
      ->capture_default_str()
      ->check(positiveNumber(1e6));
  cmd->add_option("--ready-timeout", options->ready_timeout_s,
                  "with --live: seconds to wait for a fusion center to read the measurements")
      ->capture_default_str()
      ->check(positiveNumber(3600));
  return {cmd, [options] {
            if (options->live) return runLive(*options);
            return options->info ? runInfo(*options) : runOffline(*options);
          }};
}

}  // namespace sensornet::launcher
