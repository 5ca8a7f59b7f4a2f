#include "status_command.hpp"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "sensornet/launcher/live_runs.hpp"
#include "sensornet/launcher/run_files.hpp"
#include "sensornet/launcher/run_follower.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/launcher/run_view.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kWaitStep{50};

struct StatusOptions {
  wire::RunOptions run;
  // An upper bound: it answers as soon as every sensor of the scenario has (or is known dead).
  // Discovery under DDS Security takes seconds for a handful of sensors.
  double wait_s = 10.0;
  bool json = false;
};

// Follows the run for up to `wait`; returns early once the scenario, a schedule and every sensor
// of the scenario (or the news of its death) are in.
RunView collectStatus(const dds::DomainConfig& config, const std::string& run_id,
                      std::chrono::nanoseconds wait) {
  RunFollower follower(config);
  RunViewConfig lines_unsaid;
  lines_unsaid.run_id = run_id;
  lines_unsaid.keep_lines = false;
  RunView view(lines_unsaid);
  const auto deadline = Clock::now() + wait;
  while (Clock::now() < deadline && !(view.newestSchedule() && view.allSensorsAccounted())) {
    follower.pollInto(view, kWaitStep);
  }
  return view;
}

std::string stateOf(const SensorView& s) {
  return s.state ? std::string(wordOf(*s.state)) : std::string(s.failed ? "failed" : "unknown");
}

nlohmann::json toJson(const RunView& view, const std::string& run_id) {
  nlohmann::json sensors = nlohmann::json::array();
  for (const auto& [id, row] : view.sensors()) {
    if (!row.state && !row.failed) continue;
    sensors.push_back({{"sensor_id", id},
                       {"state", stateOf(row)},
                       {"alive", row.alive},
                       {"failed", row.failed},
                       {"episode", row.episode},
                       {"schedule_version", row.schedule_version},
                       {"rate_hz", row.rate_hz},
                       {"sent_in_episode", row.sent_in_episode},
                       {"sent_total", row.sent_total},
                       {"write_timeouts", row.write_timeouts},
                       {"pid", row.process_id},
                       {"detail", row.detail}});
  }
  nlohmann::json schedule = nullptr;
  if (const auto& s = view.newestSchedule()) {
    schedule = {{"version", s->version},
                {"surrogate", s->surrogate},
                {"effective_episode", s->effective_episode},
                {"effective_time_s", s->effective_time_s},
                {"bracket", {{"info", s->bracket_lower}, {"cov", s->bracket_upper}}}};
  }
  nlohmann::json doc = {{"run_id", run_id}, {"schedule", schedule}, {"sensors", sensors}};
  if (const auto& scenario = view.scenario()) doc["sensor_count"] = scenario->sensor_count;
  return doc;
}

void printText(const RunView& view, const std::string& run_id) {
  std::size_t answered = 0;
  for (const auto& [id, row] : view.sensors()) answered += row.state.has_value() ? 1 : 0;
  std::printf("run %s: %zu sensor(s) answered", run_id.c_str(), answered);
  if (const auto& scenario = view.scenario()) std::printf(" of %u", scenario->sensor_count);
  std::printf("\n%6s  %-8s  %7s  %8s  %9s  %10s  %8s\n", "sensor", "state", "episode", "schedule",
              "rate (Hz)", "sent", "pid");
  for (const auto& [id, row] : view.sensors()) {
    if (!row.state && !row.failed) continue;
    std::printf("%6u  %-8s  %7u  %8s  %9.4g  %10llu  %8d%s%s\n", id, stateOf(row).c_str(),
                row.episode, ("v" + std::to_string(row.schedule_version)).c_str(), row.rate_hz,
                static_cast<unsigned long long>(row.sent_total), row.process_id,
                row.alive ? "" : "  (gone)", row.detail.empty() ? "" : ("  " + row.detail).c_str());
  }
  if (const auto& s = view.newestSchedule()) {
    std::printf("schedule: version %u (%s) from episode %u at t = %g s, bracket [%.6g, %.6g]\n",
                s->version, s->surrogate.c_str(), s->effective_episode, s->effective_time_s,
                s->bracket_lower, s->bracket_upper);
  } else {
    std::printf("schedule: none seen\n");
  }
}

// Why nothing may have answered, as far as this host can tell (to follow "... within 2 s").
std::string likelyCause(const LiveRun& run, const StatusOptions& options) {
  if (options.run.security_dir.empty()) {
    if (const auto dir = securityOfLauncher(run.launcher_pid)) {
      return "; run " + run.run_id + " is secured (its launcher, pid " +
             std::to_string(run.launcher_pid) + ", runs with --security " + *dir +
             ") and answers only with --security: sensornet status --run-id " + run.run_id +
             " --security " + *dir;
    }
  }
  return " (is it running? start one with `sensornet launch SCENARIO`; a secured run answers "
         "only with --security, a run across --hosts only with --cyclone-config <its log "
         "dir>/cyclone-launcher.xml)";
}

int runStatus(StatusOptions options) {
  const LiveRun run = chooseLiveRun(options.run.run_id, options.run.domain_id);
  options.run.run_id = run.run_id;
  const dds::DomainConfig config = options.run.domainConfig();
  const RunView view = collectStatus(config, options.run.run_id,
                                     std::chrono::duration_cast<std::chrono::nanoseconds>(
                                         std::chrono::duration<double>(options.wait_s)));
  const bool nothing = !view.answered();
  if (options.json) {
    printJson(toJson(view, options.run.run_id));
  } else if (!nothing) {
    printText(view, options.run.run_id);
  }
  if (nothing) {
    std::fprintf(stderr, "sensornet status: nothing of run %s answered within %g s%s\n",
                 options.run.run_id.c_str(), options.wait_s, likelyCause(run, options).c_str());
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

Subcommand addStatusCommand(CLI::App& app) {
  auto options = std::make_shared<StatusOptions>();
  CLI::App* cmd = app.add_subcommand(
      "status",
      "Show the sensors of a running emulation (state, episode, schedule version, current "
      "rate, measurements sent, process id) and the latest schedule version. Example:\n"
      "  sensornet status --json");
  wire::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  cmd->get_option("--run-id")
      ->description(
          "the run to look at (default: the one run live on this host; with several, "
          "it lists them and asks)");
  cmd->add_option("--wait", options->wait_s,
                  "at most this many seconds to listen; it answers as soon as every sensor of "
                  "the scenario has")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", options->json,
                "print {\"run_id\", \"schedule\", \"sensor_count\", \"sensors\": [...]} as one "
                "JSON line");
  return {cmd, [options] { return runStatus(*options); }};
}

}  // namespace sensornet::launcher
