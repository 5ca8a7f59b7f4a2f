#include "progress_watcher.hpp"

#include <cstdio>

#include "sensornet/dds/wire.hpp"

namespace sensornet::launcher {
namespace {

constexpr dds_attach_t kReports = 1;

}  // namespace

std::string formatProgress(const sensornet_Report& report, int episodes_planned) {
  const sensornet_RunSummary& s = report.summary;
  const double ci95 = 0.5 * (s.realized_ci95_high - s.realized_ci95_low);
  char line[256];
  std::snprintf(line, sizeof line,
                "[%u/%d] episode %u: realized %.4g, running mean %.4g \u00b1 %.2g (95%%), "
                "bracket [%.4g, %.4g]",
                s.episodes, episodes_planned, report.episode, report.realized_cost,
                s.realized_mean, ci95,
                s.bracket_lower_mean, s.bracket_upper_mean);
  std::string text = line;
  const auto versions = dds::viewSequence(report.schedule_versions);
  if (!versions.empty() && (versions.size() > 1 || versions.front() != 1)) {
    text += ", schedule ";
    for (std::size_t i = 0; i < versions.size(); ++i) {
      text += (i == 0 ? "v" : "\u2192v") + std::to_string(versions[i]);
    }
  }
  return text;
}

ProgressWatcher::ProgressWatcher(const dds::DomainConfig& config, int episodes_planned)
    : domain_(config),
      participant_(domain_),
      topic_(participant_),
      reader_(participant_, topic_),
      has_data_(reader_),
      waitset_(participant_),
      episodes_planned_(episodes_planned) {
  waitset_.attach(has_data_, kReports);
}

void ProgressWatcher::poll(std::chrono::milliseconds wait) {
  if (waitset_.wait(wait).timedOut()) return;
  const dds::Batch<sensornet_Report> batch = reader_.take();
  for (const auto& received : batch.samples) {
    const sensornet_Report& report = *received.sample;
    if (!printed_.insert(report.episode).second) continue;
    std::fprintf(stderr, "%s\n", formatProgress(report, episodes_planned_).c_str());
  }
}

}  // namespace sensornet::launcher
