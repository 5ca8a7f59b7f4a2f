#include "replay_command.hpp"

#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/mcap.hpp"

namespace sensornet::launcher {
namespace {

struct ReplayOptions {
  std::string path;
  bool info = false;
  bool json = false;
};

std::string utcOf(std::uint64_t ns) {
  const auto seconds = static_cast<std::time_t>(ns / 1'000'000'000ULL);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[40];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
  char with_ms[48];
  std::snprintf(with_ms, sizeof with_ms, "%s.%03lluZ", text,
                static_cast<unsigned long long>((ns / 1'000'000ULL) % 1000ULL));
  return with_ms;
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

}  // namespace

Subcommand addReplayCommand(CLI::App& app) {
  auto options = std::make_shared<ReplayOptions>();
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Read a recording of a run (sensornet launch --record RUN.mcap). With --info: what it "
      "holds, like `mcap info` (run metadata, time span, per topic and partition the schema and "
      "message count). Re-fusing a recording is not built yet. Example:\n  sensornet replay "
      "run.mcap --info");
  cmd->add_option("RECORDING", options->path, "an MCAP file of sensornet launch --record")
      ->required();
  cmd->add_flag("--info", options->info, "print what the recording holds");
  cmd->add_flag("--json", options->json, "with --info: one JSON line instead of the table");
  return {cmd, [options] {
            if (!options->info) {
              throw InputError("sensornet replay", "--info",
                               "--info (re-fusing a recording is not built yet)");
            }
            return runInfo(*options);
          }};
}

}  // namespace sensornet::launcher
