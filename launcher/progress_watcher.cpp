#include "progress_watcher.hpp"

#include <cmath>
#include <cstdio>
#include <thread>

#include "sensornet/dds/wire.hpp"

namespace sensornet::launcher {
namespace {

constexpr dds_attach_t kReports = 1;
constexpr dds_attach_t kControls = 2;
constexpr std::chrono::milliseconds kProbeStep{20};

}  // namespace

std::string formatProgress(const sensornet_Report& report, int episodes_planned) {
  const sensornet_RunSummary& s = report.summary;
  char line[320];
  // The interval needs two complete episodes; it is Student's t, clipped at zero below.
  char interval[96] = "";
  if (s.episodes_complete >= 2) {
    std::snprintf(interval, sizeof interval, " (95%%: [%.4g, %.4g])", s.realized_ci95_low,
                  s.realized_ci95_high);
  }
  std::snprintf(line, sizeof line,
                "[%u/%d] episode %u: realized %.4g, mean %.4g over %u complete%s, bracket "
                "[%.4g, %.4g]",
                s.episodes, episodes_planned, report.episode, report.realized_cost, s.realized_mean,
                s.episodes_complete, interval, s.bracket_lower_mean, s.bracket_upper_mean);
  std::string text = line;
  const auto versions = dds::viewSequence(report.schedule_versions);
  if (!versions.empty() && (versions.size() > 1 || versions.front() != 1)) {
    text += ", schedule ";
    for (std::size_t i = 0; i < versions.size(); ++i) {
      text += (i == 0 ? "v" : "\u2192v") + std::to_string(versions[i]);
    }
  }
  if (!std::isfinite(report.realized_cost)) {
    // No cost at all: the fusion center was not there to fuse it (it died and was restarted).
    const std::string head = line;
    text = head.substr(0, head.find(": realized")) +
           ": NOT FUSED (the fusion center restarted during it; left out of the statistics)";
    return text;
  }
  if (!report.complete) {
    std::uint64_t sent = 0, received = 0;
    for (const sensornet_SensorCounts& c : dds::viewSequence(report.counts)) {
      sent += c.sent;
      received += c.received;
    }
    text += "; INCOMPLETE: " + std::to_string(received) + " of " + std::to_string(sent) +
            " sent measurements received (left out of the statistics)";
  }
  return text;
}

ProgressWatcher::ProgressWatcher(const dds::DomainConfig& config, int episodes_planned,
                                 double horizon_s, int sensor_count)
    : domain_(config),
      participant_(domain_),
      topic_(participant_),
      scenario_topic_(participant_),
      control_topic_(participant_),
      reader_(participant_, topic_),
      scenario_reader_(participant_, scenario_topic_),
      control_reader_(participant_, control_topic_),
      status_topic_(participant_),
      status_reader_(participant_, status_topic_),
      has_data_(reader_),
      has_control_(control_reader_),
      waitset_(participant_),
      episodes_planned_(episodes_planned),
      horizon_s_(horizon_s),
      sensor_count_(sensor_count) {
  waitset_.attach(has_data_, kReports);
  waitset_.attach(has_control_, kControls);
}

bool ProgressWatcher::seesLiveRun(std::chrono::milliseconds wait) const {
  const auto until = std::chrono::steady_clock::now() + wait;
  for (;;) {
    if (scenario_reader_.matchedWriters() > 0 || reader_.matchedWriters() > 0) return true;
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(kProbeStep);
  }
}

void ProgressWatcher::poll(std::chrono::milliseconds wait) {
  if (!episode_) takeStatuses();
  const dds::WaitResult result = waitset_.wait(wait);
  if (result.timedOut()) return;
  if (result.triggered(kControls)) takeControls();
  if (!result.triggered(kReports)) return;
  const dds::Batch<sensornet_Report> batch = reader_.take();
  for (const auto& received : batch.samples) {
    const sensornet_Report& report = *received.sample;
    if (!printed_.insert(report.episode)) continue;
    std::fprintf(stderr, "%s\n", formatProgress(report, episodes_planned_).c_str());
  }
}

void ProgressWatcher::takeStatuses() {
  for (const auto& received : status_reader_.take().samples) {
    if (received.sample->schedule_version >= 1) ready_.insert(received.sample->sensor_id);
  }
  const auto now = std::chrono::steady_clock::now();
  const bool all = static_cast<int>(ready_.size()) >= sensor_count_;
  if (ready_.size() == ready_said_ || (!all && now - ready_said_at_ < std::chrono::seconds(1))) {
    return;
  }
  sayReady(ready_.size());
}

void ProgressWatcher::sayAllReady() {
  takeStatuses();
  if (static_cast<int>(ready_said_) < sensor_count_) {
    sayReady(static_cast<std::size_t>(sensor_count_));
  }
}

void ProgressWatcher::sayReady(std::size_t count) {
  const auto now = std::chrono::steady_clock::now();
  ready_said_ = count;
  ready_said_at_ = now;
  std::fprintf(stderr, "ready %zu/%d sensors (%.1f s)\n", count, sensor_count_,
               std::chrono::duration<double>(now - created_).count());
}

void ProgressWatcher::takeControls() {
  const dds::Batch<sensornet_EpisodeControl> batch = control_reader_.take();
  for (const auto& received : batch.samples) {
    const sensornet_EpisodeControl& c = *received.sample;
    if (c.command == sensornet_RUN_SHUTDOWN) {
      shut_down_ = true;
    } else if (c.command == sensornet_EPISODE_START && (!episode_ || c.episode >= *episode_)) {
      if (!episode_) sayAllReady();  // the coordinator starts only once every sensor is ready
      if (episode_ && c.episode > *episode_) {
        previous_episode_ = episode_;
        previous_clock_ = clock_;
      }
      episode_ = c.episode;
      clock_ = {c.start_wall_time_ns, c.time_scale};
    }
  }
}

RunPosition ProgressWatcher::positionAt(std::int64_t wall_ns) const {
  if (!episode_ || shut_down_) return {};
  // The next episode is announced while the current one runs: before its start, the position
  // is in the one announced before it.
  const bool before_latest = previous_episode_ && wall_ns < clock_.start_wall_ns;
  const emulator::EpisodeClock& clock = before_latest ? previous_clock_ : clock_;
  RunPosition at{before_latest ? previous_episode_ : episode_, std::nullopt};
  const double t = clock.emulatedAt(wall_ns);
  if (t >= 0.0 && t <= horizon_s_) at.emulated_time_s = t;
  return at;
}

}  // namespace sensornet::launcher
