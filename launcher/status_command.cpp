#include "status_command.hpp"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "run_files.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/run_options.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr dds_attach_t kStatuses = 1;
constexpr dds_attach_t kSchedules = 2;
constexpr dds_attach_t kScenarios = 3;
constexpr std::chrono::milliseconds kWaitStep{50};

struct StatusOptions {
  emulator::RunOptions run;
  double wait_s = 2.0;
  bool json = false;
};

struct SensorRow {
  std::uint32_t sensor_id = 0;
  std::string state;
  std::uint32_t episode = 0;
  std::uint32_t schedule_version = 0;
  double rate_hz = 0.0;
  std::uint64_t sent_in_episode = 0;
  std::uint64_t sent_total = 0;
  std::uint64_t write_timeouts = 0;
  std::int32_t pid = 0;
  std::int64_t wall_time_ns = 0;
  std::string detail;
  bool alive = true;  // false once the sensor's process left or died (no writers)
};

struct ScheduleRow {
  std::uint32_t version = 0;
  std::string surrogate;
  std::uint32_t effective_episode = 0;
  double effective_time_s = 0.0;
  double bracket_lower = 0.0;
  double bracket_upper = 0.0;
};

struct RunStatus {
  std::map<std::uint32_t, SensorRow> sensors;
  std::optional<ScheduleRow> schedule;        // the highest version seen
  std::optional<std::uint32_t> sensor_count;  // from the Scenario topic
  [[nodiscard]] bool complete() const {
    return sensor_count && schedule && sensors.size() >= *sensor_count;
  }
};

SensorRow toRow(const sensornet_SensorStatus& s) {
  SensorRow row;
  row.sensor_id = s.sensor_id;
  row.state = emulator::sensorStateName(s.state);
  row.episode = s.episode;
  row.schedule_version = s.schedule_version;
  row.rate_hz = s.current_rate_hz;
  row.sent_in_episode = s.sent_in_episode;
  row.sent_total = s.sent_total;
  row.write_timeouts = s.write_timeouts;
  row.pid = s.process_id;
  row.wall_time_ns = s.wall_time_ns;
  row.detail = std::string(dds::viewString(s.detail));
  return row;
}

// Reads what the run's sensors and coordinator have published, for up to `wait`; returns early
// once every sensor of the scenario and a schedule have been seen.
RunStatus collectStatus(const dds::DomainConfig& config, const std::string& run_id,
                        std::chrono::nanoseconds wait) {
  dds::Domain domain(config);
  dds::Participant participant(domain);
  dds::Topic<sensornet_SensorStatus> status_topic(participant);
  dds::Topic<sensornet_Schedule> schedule_topic(participant);
  dds::Topic<sensornet_Scenario> scenario_topic(participant);
  dds::Reader<sensornet_SensorStatus> statuses(participant, status_topic);
  dds::Reader<sensornet_Schedule> schedules(participant, schedule_topic);
  dds::Reader<sensornet_Scenario> scenarios(participant, scenario_topic);
  dds::ReadCondition has_status(statuses), has_schedule(schedules), has_scenario(scenarios);
  dds::WaitSet waitset(participant);
  waitset.attach(has_status, kStatuses);
  waitset.attach(has_schedule, kSchedules);
  waitset.attach(has_scenario, kScenarios);

  RunStatus status;
  const auto deadline = Clock::now() + wait;
  while (Clock::now() < deadline && !status.complete()) {
    (void)waitset.wait(kWaitStep);
    const auto batch = statuses.take();
    for (const auto& received : batch.samples) {
      const sensornet_SensorStatus& s = *received.sample;
      if (dds::viewString(s.run_id) != run_id) continue;
      SensorRow& row = status.sensors[s.sensor_id];
      if (s.wall_time_ns >= row.wall_time_ns) row = toRow(s);
      row.alive = received.info.instance_state == dds::InstanceState::Alive;
    }
    for (const auto& change : batch.changes) {
      auto found = status.sensors.find(change.key->sensor_id);
      if (found != status.sensors.end()) {
        found->second.alive = change.info.instance_state == dds::InstanceState::Alive;
      }
    }
    for (const auto& received : schedules.take().samples) {
      const sensornet_Schedule& s = *received.sample;
      if (dds::viewString(s.run_id) != run_id) continue;
      if (status.schedule && status.schedule->version >= s.version) continue;
      status.schedule = ScheduleRow{s.version,           std::string(dds::viewString(s.surrogate)),
                                    s.effective_episode, s.effective_time_s,
                                    s.bracket_lower,     s.bracket_upper};
    }
    for (const auto& received : scenarios.take().samples) {
      if (dds::viewString(received.sample->run_id) == run_id) {
        status.sensor_count = received.sample->sensor_count;
      }
    }
  }
  return status;
}

nlohmann::json toJson(const RunStatus& status, const std::string& run_id) {
  nlohmann::json sensors = nlohmann::json::array();
  for (const auto& [id, row] : status.sensors) {
    sensors.push_back({{"sensor_id", id},
                       {"state", row.state},
                       {"alive", row.alive},
                       {"episode", row.episode},
                       {"schedule_version", row.schedule_version},
                       {"rate_hz", row.rate_hz},
                       {"sent_in_episode", row.sent_in_episode},
                       {"sent_total", row.sent_total},
                       {"write_timeouts", row.write_timeouts},
                       {"pid", row.pid},
                       {"detail", row.detail}});
  }
  nlohmann::json schedule = nullptr;
  if (const auto& s = status.schedule) {
    schedule = {{"version", s->version},
                {"surrogate", s->surrogate},
                {"effective_episode", s->effective_episode},
                {"effective_time_s", s->effective_time_s},
                {"bracket", {{"info", s->bracket_lower}, {"cov", s->bracket_upper}}}};
  }
  nlohmann::json doc = {{"run_id", run_id}, {"schedule", schedule}, {"sensors", sensors}};
  if (status.sensor_count) doc["sensor_count"] = *status.sensor_count;
  return doc;
}

void printText(const RunStatus& status, const std::string& run_id) {
  std::printf("run %s: %zu sensor(s) answered", run_id.c_str(), status.sensors.size());
  if (status.sensor_count) std::printf(" of %u", *status.sensor_count);
  std::printf("\n%6s  %-8s  %7s  %8s  %9s  %10s  %8s\n", "sensor", "state", "episode", "schedule",
              "rate (Hz)", "sent", "pid");
  for (const auto& [id, row] : status.sensors) {
    std::printf("%6u  %-8s  %7u  %8s  %9.4g  %10llu  %8d%s%s\n", id, row.state.c_str(), row.episode,
                ("v" + std::to_string(row.schedule_version)).c_str(), row.rate_hz,
                static_cast<unsigned long long>(row.sent_total), row.pid,
                row.alive ? "" : "  (gone)", row.detail.empty() ? "" : ("  " + row.detail).c_str());
  }
  if (const auto& s = status.schedule) {
    std::printf("schedule: version %u (%s) from episode %u at t = %g s, bracket [%.6g, %.6g]\n",
                s->version, s->surrogate.c_str(), s->effective_episode, s->effective_time_s,
                s->bracket_lower, s->bracket_upper);
  } else {
    std::printf("schedule: none seen\n");
  }
}

int runStatus(StatusOptions options) {
  options.run.run_id = chooseRunId(options.run.run_id, options.run.domain_id);
  const dds::DomainConfig config = options.run.domainConfig();
  const RunStatus status = collectStatus(config, options.run.run_id,
                                         std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::duration<double>(options.wait_s)));
  const bool nothing = status.sensors.empty() && !status.schedule;
  if (options.json) {
    printJson(toJson(status, options.run.run_id));
  } else if (!nothing) {
    printText(status, options.run.run_id);
  }
  if (nothing) {
    std::fprintf(stderr,
                 "sensornet status: nothing of run %s answered within %g s (is it running? "
                 "start one with `sensornet launch SCENARIO`)\n",
                 options.run.run_id.c_str(), options.wait_s);
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
  emulator::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  cmd->get_option("--run-id")
      ->description("the run to look at (default: the run last launched on this host)");
  cmd->add_option("--wait", options->wait_s, "seconds to listen for the sensors")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", options->json,
                "print {\"run_id\", \"schedule\", \"sensors\": [...]} as one JSON line");
  return {cmd, [options] { return runStatus(*options); }};
}

}  // namespace sensornet::launcher
