#include "sensornet/launcher/command_client.hpp"

#include <spdlog/spdlog.h>

#include <span>

#include "sensornet/dds/wire.hpp"
#include "sensornet/wire/messages.hpp"

namespace sensornet::launcher {
namespace {

constexpr std::int64_t kResendAfterNs = 2'000'000'000;
constexpr dds_attach_t kReplies = 1;
constexpr std::chrono::milliseconds kWaitStep{100};

}  // namespace

CommandClient::CommandClient(const dds::Participant& participant, std::string run_id,
                             emulator::CommandSender sender, std::string issuer)
    : run_id_(std::move(run_id)),
      issuer_(std::move(issuer)),
      command_topic_(participant),
      reply_topic_(participant),
      commands_(participant, command_topic_,
                dds::endpointQosIn<sensornet_Command>(
                    emulator::commandPartition(participant.partition(), sender))),
      replies_(participant, reply_topic_),
      has_reply_(replies_),
      waitset_(participant) {
  waitset_.attach(has_reply_, kReplies);
}

bool CommandClient::waitForCoordinator(std::chrono::nanoseconds wait) const {
  return commands_.waitForReaders(1, wait);
}

std::uint64_t CommandClient::send(CommandRequest request) {
  // Unique per run: wall time in ns, kept above every earlier command's even within one tick.
  std::uint64_t id = static_cast<std::uint64_t>(emulator::wallNowNs());
  if (id <= last_id_) id = last_id_ + 1;
  last_id_ = id;
  pending_.push_back({id, std::move(request), 0, false});
  write(pending_.back());
  return id;
}

void CommandClient::write(Pending& pending) {
  const CommandRequest& r = pending.request;
  sensornet_Command command{};
  command.run_id = dds::borrowString(run_id_);
  command.command_id = pending.id;
  command.kind = r.kind;
  command.surrogate = dds::borrowString(r.surrogate);
  dds::borrowSequence(command.sensor_ids, std::span<const std::uint32_t>(r.sensor_ids));
  dds::borrowSequence(command.budget, std::span<const double>(r.budget));
  command.schedule_json = dds::borrowString(r.schedule_json);
  command.issuer = dds::borrowString(issuer_);
  command.issued_wall_time_ns = emulator::wallNowNs();
  command.detail = dds::borrowString(r.detail);
  pending.sent_wall_ns = command.issued_wall_time_ns;
  if (commands_.write(command) == dds::WriteResult::TimedOut) {
    spdlog::warn("command {} timed out on the wire; it is sent again", pending.id);
  }
}

std::vector<std::pair<std::uint64_t, CommandReply>> CommandClient::poll() {
  std::vector<std::pair<std::uint64_t, CommandReply>> replies;
  for (const auto& received : replies_.take().samples) {
    const sensornet_CommandReply& r = *received.sample;
    if (dds::viewString(r.run_id) != run_id_) continue;
    for (Pending& pending : pending_) {
      if (pending.id != r.command_id || pending.answered) continue;
      pending.answered = true;
      replies.emplace_back(pending.id, CommandReply{r.accepted, r.schedule_version,
                                                    std::string(dds::viewString(r.reason))});
    }
  }
  const std::int64_t now = emulator::wallNowNs();
  for (Pending& pending : pending_) {
    if (!pending.answered && now - pending.sent_wall_ns > kResendAfterNs) write(pending);
  }
  return replies;
}

std::optional<CommandReply> CommandClient::await(std::uint64_t id,
                                                 std::chrono::steady_clock::time_point deadline) {
  while (std::chrono::steady_clock::now() < deadline) {
    (void)waitset_.wait(kWaitStep);
    for (auto& [answered, reply] : poll()) {
      if (answered == id) return std::move(reply);
    }
  }
  return std::nullopt;
}

}  // namespace sensornet::launcher
