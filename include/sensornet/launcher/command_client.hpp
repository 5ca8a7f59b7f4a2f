#pragma once
// The one client for the commands the launcher's programs send a run's coordinator (`sensornet
// replan`'s re-plans, the launcher's failure notices): each Command goes out with an id unique
// in the run, is written again every couple of seconds until its reply comes (a restarted
// coordinator knows the ids it answered, from its journal, and answers a repeat the same way),
// and a reply is matched to its command by run and id.
//
//   CommandClient client(participant, run_id);
//   if (!client.waitForCoordinator(5s)) ...;                // a replan needs someone listening
//   const std::uint64_t id = client.send({sensornet_COMMAND_REPLAN, "cov"});   // at once
//   for (const auto& [id, reply] : client.poll()) ...;      // replies since; resends what is due
//   std::optional<CommandReply> r = client.await(id, deadline);   // or nullopt at the deadline

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/launcher/supervisor.hpp"

namespace sensornet::launcher {

// The coordinator's answer to a command (the supervisor core's word for it).
using CommandReply = FailureReply;

// What a command says besides its run and id.
struct CommandRequest {
  sensornet_CommandKind kind = sensornet_COMMAND_REPLAN;
  std::string surrogate;
  std::vector<std::uint32_t> sensor_ids;
  std::vector<double> budget;
  std::string schedule_json;
  std::string detail;
};

class CommandClient {
 public:
  // Writes in the Command partition of `sender` (run_partitions.hpp): what the coordinator
  // knows it by, authenticated in a secured run; `issuer` is free text for its log.
  CommandClient(const dds::Participant& participant, std::string run_id,
                emulator::CommandSender sender, std::string issuer);

  // True once a coordinator's command reader is matched, within `wait`.
  [[nodiscard]] bool waitForCoordinator(std::chrono::nanoseconds wait) const;
  // Writes the command once and keeps it for resending; returns its id.
  std::uint64_t send(CommandRequest request);
  // The replies that came since the last call; writes again what is still unanswered after the
  // resend interval.
  [[nodiscard]] std::vector<std::pair<std::uint64_t, CommandReply>> poll();
  // Polls until the reply to `id` comes (the reply) or `deadline` passes (nullopt).
  [[nodiscard]] std::optional<CommandReply> await(std::uint64_t id,
                                                  std::chrono::steady_clock::time_point deadline);

 private:
  struct Pending {
    std::uint64_t id = 0;
    CommandRequest request;
    std::int64_t sent_wall_ns = 0;
    bool answered = false;
  };
  void write(Pending& pending);

  std::string run_id_;
  std::string issuer_;
  dds::Topic<sensornet_Command> command_topic_;
  dds::Topic<sensornet_CommandReply> reply_topic_;
  dds::Writer<sensornet_Command> commands_;
  dds::Reader<sensornet_CommandReply> replies_;
  dds::ReadCondition has_reply_;
  dds::WaitSet waitset_;
  std::vector<Pending> pending_;
  std::uint64_t last_id_ = 0;
};

}  // namespace sensornet::launcher
