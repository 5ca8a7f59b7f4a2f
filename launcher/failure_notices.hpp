#pragma once
// The launcher's word to the coordinator that sensors died: when a sensor agent ends (killed, a
// scripted crash, a failure), the sensors it hosted are dead for the rest of the run, and the
// coordinator applies the run's --on-sensor-failure policy (re-plan among the survivors,
// continue, or stop). The notice is a Command of kind COMMAND_SENSORS_FAILED, sent again every
// couple of seconds until the coordinator answers (it may itself be restarting: a restarted
// coordinator knows the command ids it answered and answers a repeat the same way).
//
//   FailureNotices notices(progress.participant(), run_id);
//   notices.send("sensor_agent-3", {3}, "killed by signal 9 (Killed)");   // at once, no wait
//   for (const auto& [process, reply] : notices.poll()) ...;   // every watch step: new replies,
//                                                              // resends

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/launcher/supervisor.hpp"  // FailureReply

namespace sensornet::launcher {

class FailureNotices {
 public:
  FailureNotices(const dds::Participant& participant, std::string run_id);

  void send(const std::string& process, const std::vector<int>& sensors,
            const std::string& detail);
  // Reads the coordinator's replies and resends what is still unanswered after kResendAfter;
  // returns the replies that came meanwhile, with the process each notice was about.
  [[nodiscard]] std::vector<std::pair<std::string, FailureReply>> poll();

 private:
  struct Notice {
    std::string process;
    std::uint64_t command_id = 0;
    std::vector<std::uint32_t> sensors;
    std::string detail;
    std::int64_t sent_wall_ns = 0;
    std::optional<FailureReply> reply;
  };
  void write(Notice& notice);

  std::string run_id_;
  dds::Topic<sensornet_Command> command_topic_;
  dds::Topic<sensornet_CommandReply> reply_topic_;
  dds::Writer<sensornet_Command> commands_;
  dds::Reader<sensornet_CommandReply> replies_;
  std::vector<Notice> notices_;
};

}  // namespace sensornet::launcher
