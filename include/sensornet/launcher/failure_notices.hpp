#pragma once
// The launcher's word to the coordinator that sensors died: when a sensor agent ends (killed, a
// scripted crash, a failure), the sensors it hosted are dead for the rest of the run, and the
// coordinator applies the run's --on-sensor-failure policy (re-plan among the survivors,
// continue, or stop). The notice is a Command of kind COMMAND_SENSORS_FAILED, sent through the
// one command client (command_client.hpp), which sends it again until the coordinator answers.
//
//   FailureNotices notices(progress.participant(), run_id);
//   notices.send("sensor_agent-3", {3}, "killed by signal 9 (Killed)");   // at once, no wait
//   for (const auto& [process, reply] : notices.poll()) ...;   // every watch step: new replies

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/launcher/command_client.hpp"

namespace sensornet::launcher {

class FailureNotices {
 public:
  FailureNotices(const dds::Participant& participant, std::string run_id);

  void send(const std::string& process, const std::vector<int>& sensors,
            const std::string& detail);
  // The replies that came meanwhile, with the process each notice was about; resends what is
  // still unanswered.
  [[nodiscard]] std::vector<std::pair<std::string, FailureReply>> poll();

 private:
  CommandClient client_;
  std::map<std::uint64_t, std::string> process_of_;  // command id -> the process it is about
};

}  // namespace sensornet::launcher
