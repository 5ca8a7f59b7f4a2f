#pragma once
// The launcher's view of a run's progress: its own DDS participant in the run's domain and
// partition reads the fusion center's Report topic and prints one line per episode on standard
// error.
//
//   ProgressWatcher progress(run.domainConfig(), 20);
//   progress.poll(std::chrono::milliseconds(50));   // prints the episodes reported meanwhile
//   // episode 3/20: realized 12.3, running mean 11.8 ± 0.9 (95%), bracket [10.2, 30.1]

#include <chrono>
#include <cstdint>
#include <set>
#include <string>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"

namespace sensornet::launcher {

// The progress line of one episode's report.
[[nodiscard]] std::string formatProgress(const sensornet_Report& report, int episodes_planned);

class ProgressWatcher {
 public:
  ProgressWatcher(const dds::DomainConfig& config, int episodes_planned);

  // Waits up to `wait` for reports and prints a line for each episode not printed yet.
  void poll(std::chrono::milliseconds wait);
  [[nodiscard]] std::size_t episodesSeen() const noexcept { return printed_.size(); }

 private:
  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Report> topic_;
  dds::Reader<sensornet_Report> reader_;
  dds::ReadCondition has_data_;
  dds::WaitSet waitset_;
  int episodes_planned_;
  std::set<std::uint32_t> printed_;
};

}  // namespace sensornet::launcher
