#include "sensornet/launcher/progress_watcher.hpp"

#include <cstdio>

#include "sensornet/wire/messages.hpp"

namespace sensornet::launcher {
namespace {

RunViewConfig launcherView(int episodes_planned) {
  RunViewConfig config;
  config.episodes_planned = static_cast<std::uint32_t>(episodes_planned);
  config.keep_lines = false;  // it prints only the episodes' lines
  config.keep_reports = true;
  return config;
}

}  // namespace

ProgressWatcher::ProgressWatcher(const dds::DomainConfig& config, int episodes_planned,
                                 double /*horizon_s*/, int sensor_count)
    : follower_(config), view_(launcherView(episodes_planned)), sensor_count_(sensor_count) {}

void ProgressWatcher::poll(std::chrono::milliseconds wait) {
  follower_.pollInto(view_, wait);
  for (const EpisodeReportSeen& report : view_.takeReports()) {
    std::fprintf(stderr, "%s\n", formatProgress(report, view_.episodesPlanned()).c_str());
  }
  if (started_) return;
  const RunPosition at = view_.positionAt(emulator::wallNowNs());
  if (at.episode || view_.ended()) {
    // The coordinator starts only once every sensor is ready; a run that ended without an
    // episode (its coordinator gave up waiting) did not have them all.
    started_ = true;
    const bool ran = at.episode.has_value() || view_.episodesReported() > 0;
    if (ran && static_cast<int>(ready_said_) < sensor_count_) {
      sayReady(static_cast<std::size_t>(sensor_count_));
    }
    return;
  }
  const std::size_t ready = view_.sensorsReady();
  const bool all = static_cast<int>(ready) >= sensor_count_;
  const auto now = std::chrono::steady_clock::now();
  if (advice_ && now - created_ >= advice_delay_) {
    const std::string advice = advice_();
    advice_ = nullptr;
    std::fputs(advice.c_str(), stderr);
  }
  if (ready == ready_said_ || (!all && now - ready_said_at_ < std::chrono::seconds(1))) return;
  sayReady(ready);
}

void ProgressWatcher::sayReady(std::size_t count) {
  const auto now = std::chrono::steady_clock::now();
  ready_said_ = count;
  ready_said_at_ = now;
  std::fprintf(stderr, "ready %zu/%d sensors (%.1f s)\n", count, sensor_count_,
               std::chrono::duration<double>(now - created_).count());
}

}  // namespace sensornet::launcher
