#include "sensornet/launcher/failure_notices.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

namespace sensornet::launcher {

FailureNotices::FailureNotices(const dds::Participant& participant, std::string run_id)
    : client_(participant, std::move(run_id), emulator::CommandSender::Launcher,
              "sensornet launch " + std::to_string(::getpid())) {}

void FailureNotices::send(const std::string& process, const std::vector<int>& sensors,
                          const std::string& detail) {
  CommandRequest request;
  request.kind = sensornet_COMMAND_SENSORS_FAILED;
  request.sensor_ids.assign(sensors.begin(), sensors.end());
  request.detail = process + " " + detail;
  process_of_[client_.send(std::move(request))] = process;
}

std::vector<std::pair<std::string, FailureReply>> FailureNotices::poll() {
  std::vector<std::pair<std::string, FailureReply>> replies;
  for (auto& [id, reply] : client_.poll()) {
    const std::string& process = process_of_[id];
    spdlog::info("coordinator on the failure of {}: {}", process, reply.reason);
    replies.emplace_back(process, std::move(reply));
  }
  return replies;
}

}  // namespace sensornet::launcher
