#include "sensornet/launcher/run_follower.hpp"

#include <spdlog/spdlog.h>

#include <thread>

#include "sensornet/dds/wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/emulator/run_partitions.hpp"

namespace sensornet::launcher {
namespace {

constexpr std::string_view kPartitionPrefix = "sensornet/";
constexpr std::chrono::milliseconds kProbeStep{20};

ScenarioSeen scenarioOf(const sensornet_Scenario& s) {
  return {std::string(dds::viewString(s.digest)), s.sensor_count, s.state_dim, s.horizon_s, s.seed};
}

ScheduleSeen scheduleOf(const sensornet_Schedule& s) {
  return {s.version,           std::string(dds::viewString(s.surrogate)),
          s.effective_episode, s.effective_time_s,
          s.bracket_lower,     s.bracket_upper};
}

SensorStatusSeen statusOf(const sensornet_SensorStatus& s, bool alive) {
  SensorStatusSeen out;
  out.sensor_id = s.sensor_id;
  out.state = wire::sensorStateOf(s.state).value_or(emulator::SensorState::Starting);
  out.episode = s.episode;
  out.schedule_version = s.schedule_version;
  out.rate_hz = s.current_rate_hz;
  out.sent_in_episode = s.sent_in_episode;
  out.sent_total = s.sent_total;
  out.write_timeouts = s.write_timeouts;
  out.process_id = s.process_id;
  out.wall_time_ns = s.wall_time_ns;
  out.detail = std::string(dds::viewString(s.detail));
  out.alive = alive;
  return out;
}

EpisodeReportSeen reportOf(const sensornet_Report& r) {
  EpisodeReportSeen out;
  out.episode = r.episode;
  out.realized_cost = r.realized_cost;
  out.complete = r.complete;
  out.incomplete_reason = std::string(dds::viewString(r.incomplete_reason));
  const auto versions = dds::viewSequence(r.schedule_versions);
  out.schedule_versions.assign(versions.begin(), versions.end());
  for (const sensornet_SensorCounts& c : dds::viewSequence(r.counts)) {
    out.counts.push_back({c.sensor_id, c.sent, c.received, c.lost});
  }
  out.latency_median_s = r.latency_median_s;
  out.latency_p99_s = r.latency_p99_s;
  const sensornet_RunSummary& s = r.summary;
  out.summary = {s.episodes,           s.episodes_complete,  s.realized_mean,
                 s.realized_ci95_low,  s.realized_ci95_high, s.bracket_lower_mean,
                 s.bracket_upper_mean, s.meets_bracket,       s.delivered_lower_mean,
                 s.delivered_upper_mean};
  return out;
}

std::string runIdOf(const std::string& partition) {
  return partition.starts_with(kPartitionPrefix) ? partition.substr(kPartitionPrefix.size())
                                                 : std::string();
}

}  // namespace

RunFollower::RunFollower(const dds::DomainConfig& config)
    : run_id_(runIdOf(config.partition)),
      domain_(config),
      participant_(domain_),
      scenario_topic_(participant_),
      schedule_topic_(participant_),
      control_topic_(participant_),
      status_topic_(participant_),
      report_topic_(participant_),
      scenarios_(participant_, scenario_topic_),
      schedules_(participant_, schedule_topic_),
      controls_(participant_, control_topic_),
      // Every sensor process writes in its own partition (run_partitions.hpp).
      statuses_(participant_, status_topic_,
                dds::readerQosMatching<sensornet_SensorStatus>(
                    emulator::sensorPartitionPattern(participant_.partition()))),
      reports_(participant_, report_topic_),
      has_scenario_(scenarios_),
      has_schedule_(schedules_),
      has_control_(controls_),
      has_status_(statuses_),
      has_report_(reports_),
      waitset_(participant_) {
  dds_attach_t token = 0;
  for (const dds::ReadCondition* c :
       {&has_scenario_, &has_schedule_, &has_control_, &has_status_, &has_report_}) {
    waitset_.attach(*c, ++token);
  }
}

bool RunFollower::ours(const char* run_id) const {
  return run_id_.empty() || dds::viewString(run_id) == run_id_;
}

bool RunFollower::seesLiveRun(std::chrono::milliseconds wait, bool fusion_centers) const {
  const auto until = std::chrono::steady_clock::now() + wait;
  for (;;) {
    if (scenarios_.matchedWriters() > 0 || (fusion_centers && reports_.matchedWriters() > 0)) {
      return true;
    }
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(kProbeStep);
  }
}

void RunFollower::pollInto(RunView& view, std::chrono::milliseconds wait) {
  (void)waitset_.wait(wait);
  const std::int64_t now = emulator::wallNowNs();
  for (const auto& s : scenarios_.take().samples) {
    if (ours(s.sample->run_id)) view.onScenario(scenarioOf(*s.sample), now);
  }
  for (const auto& s : schedules_.take().samples) {
    if (ours(s.sample->run_id)) view.onSchedule(scheduleOf(*s.sample), now);
  }
  takeStatuses(view, now);
  if (!report_writer_seen_ && reports_.matchedWriters() > 0) report_writer_seen_ = true;
  for (const auto& s : reports_.take().samples) {
    if (!ours(s.sample->run_id)) continue;
    record(*s.sample);
    view.onReport(reportOf(*s.sample), now);
  }
  takeControls(view, now);
}

void RunFollower::recordReportsTo(const std::filesystem::path& path, int sensor_count) {
  record_ = std::make_unique<sensornet::report::EpisodeLog>(path);
  record_sensor_count_ = sensor_count;
}

void RunFollower::record(const sensornet_Report& report) {
  if (!record_ || recorded_.contains(report.episode)) return;
  try {
    record_->append(wire::episodeEntryOfReport(report, record_sensor_count_));
    recorded_.insert(report.episode);
  } catch (const std::exception& e) {  // a Report that does not fit, or a log that cannot grow
    ++reports_refused_;
    spdlog::warn("did not record the Report of episode {}: {}", report.episode, e.what());
  }
}

void RunFollower::takeStatuses(RunView& view, std::int64_t now) {
  const auto statuses = statuses_.take();
  for (const auto& s : statuses.samples) {
    if (!ours(s.sample->run_id)) continue;
    view.onSensorStatus(statusOf(*s.sample, s.info.instance_state == dds::InstanceState::Alive),
                        now);
  }
  for (const auto& change : statuses.changes) {
    if (change.info.instance_state != dds::InstanceState::Alive) {
      view.onSensorGone(change.key->sensor_id, now);
    }
  }
}

// Last in a poll: a RUN_SHUTDOWN comes after the reports and statuses taken with it.
void RunFollower::takeControls(RunView& view, std::int64_t now) {
  const auto controls = controls_.take();
  bool writer_left = false;
  for (const auto& s : controls.samples) {
    const sensornet_EpisodeControl& c = *s.sample;
    writer_left = writer_left || s.info.instance_state == dds::InstanceState::NoWriters;
    if (!ours(c.run_id)) continue;
    switch (c.command) {
      case sensornet_EPISODE_START:
        view.onEpisodeStart({c.episode,
                             {c.start_wall_time_ns, c.time_scale},
                             c.episodes_planned,
                             c.schedule_version},
                            now);
        break;
      case sensornet_EPISODE_STOP:
        view.onEpisodeStop(c.episode, now);
        break;
      case sensornet_EPISODE_SENSORS_FAILED: {
        emulator::SensorFailure failure{
            c.episode, c.failed_at_s, {}, std::string(dds::viewString(c.detail))};
        for (const std::uint32_t id : dds::viewSequence(c.failed_sensors)) {
          failure.sensors.insert(static_cast<int>(id));
        }
        view.onSensorsFailed(failure, now);
        break;
      }
      case sensornet_RUN_SHUTDOWN:
        view.onRunEnd({c.episodes_planned, c.aborted, std::string(dds::viewString(c.detail))}, now);
        break;
    }
  }
  for (const auto& change : controls.changes) {
    writer_left = writer_left || change.info.instance_state == dds::InstanceState::NoWriters;
  }
  // Whoever else joined the partition, the coordinator is the only writer of the controls: once
  // it matched and no writer is left, it has gone.
  const std::uint32_t writers = controls_.matchedWriters();
  if (writers > 0) coordinator_seen_ = true;
  if (writer_left || (coordinator_seen_ && writers == 0)) view.onCoordinatorGone(now);
}

}  // namespace sensornet::launcher
