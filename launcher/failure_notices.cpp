#include "failure_notices.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include "sensornet/dds/wire.hpp"
#include "sensornet/emulator/messages.hpp"

namespace sensornet::launcher {
namespace {

constexpr std::int64_t kResendAfterNs = 2'000'000'000;

}  // namespace

FailureNotices::FailureNotices(const dds::Participant& participant, std::string run_id)
    : run_id_(std::move(run_id)),
      command_topic_(participant),
      reply_topic_(participant),
      commands_(participant, command_topic_),
      replies_(participant, reply_topic_) {}

void FailureNotices::send(const std::string& process, const std::vector<int>& sensors,
                          const std::string& detail) {
  Notice notice;
  notice.process = process;
  // Unique per run: wall time in ns, kept above every earlier notice's even within one tick.
  notice.command_id = static_cast<std::uint64_t>(emulator::wallNowNs());
  if (!notices_.empty() && notice.command_id <= notices_.back().command_id) {
    notice.command_id = notices_.back().command_id + 1;
  }
  notice.sensors.assign(sensors.begin(), sensors.end());
  notice.detail = process + " " + detail;
  write(notice);
  notices_.push_back(std::move(notice));
}

void FailureNotices::write(Notice& notice) {
  const std::string issuer = "sensornet launch " + std::to_string(::getpid());
  const std::string none;
  sensornet_Command command{};
  command.run_id = dds::borrowString(run_id_);
  command.command_id = notice.command_id;
  command.kind = sensornet_COMMAND_SENSORS_FAILED;
  command.surrogate = dds::borrowString(none);
  dds::borrowSequence(command.sensor_ids, std::span<const std::uint32_t>(notice.sensors));
  command.schedule_json = dds::borrowString(none);
  command.issuer = dds::borrowString(issuer);
  command.issued_wall_time_ns = emulator::wallNowNs();
  command.detail = dds::borrowString(notice.detail);
  notice.sent_wall_ns = command.issued_wall_time_ns;
  if (commands_.write(command) == dds::WriteResult::TimedOut) {
    spdlog::warn("the failure notice of {} timed out; it is sent again", notice.process);
  }
}

std::vector<std::pair<std::string, FailureReply>> FailureNotices::poll() {
  std::vector<std::pair<std::string, FailureReply>> replies;
  for (const auto& received : replies_.take().samples) {
    const sensornet_CommandReply& r = *received.sample;
    if (dds::viewString(r.run_id) != run_id_) continue;
    for (Notice& notice : notices_) {
      if (notice.command_id != r.command_id || notice.reply) continue;
      notice.reply = FailureReply{r.accepted, r.schedule_version,
                                  std::string(dds::viewString(r.reason))};
      spdlog::info("coordinator on the failure of {}: {}", notice.process, notice.reply->reason);
      replies.emplace_back(notice.process, *notice.reply);
    }
  }
  const std::int64_t now = emulator::wallNowNs();
  for (Notice& notice : notices_) {
    if (!notice.reply && now - notice.sent_wall_ns > kResendAfterNs) write(notice);
  }
  return replies;
}

}  // namespace sensornet::launcher
