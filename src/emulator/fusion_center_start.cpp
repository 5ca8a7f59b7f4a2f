#include "sensornet/emulator/fusion_center_start.hpp"

#include <spdlog/spdlog.h>

#include "sensornet/report/report_files.hpp"

namespace sensornet::emulator {

void useLogsBeside(FusionCenterConfig& config, const std::string& report_path, bool resume) {
  if (!report_path.empty()) {
    const auto log_path = report::episodeLogPath(report_path);
    config.episode_log = true;
    config.episode_log_path = log_path.string();
    if (resume) {
      config.resumed_log = report::readEpisodeLog(log_path);
      spdlog::info("resuming from {} episodes in the episode log {}", config.resumed_log->size(),
                   log_path.string());
      config.resumed_faults = report::readFaultLog(report::faultLogPath(report_path));
    }
  }
  if (resume && !config.resumed_log) config.resumed_log.emplace();
}

}  // namespace sensornet::emulator
