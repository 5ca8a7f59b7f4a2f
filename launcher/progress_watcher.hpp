#pragma once
// The launcher's view of a run: its own DDS participant in the run's domain and partition
// reads the fusion center's Report topic and prints one line per episode on standard error,
// follows the coordinator's EpisodeControl topic to know where the run is (which episode, what
// emulated time), and, before the launcher starts anything, tells whether a run with this id
// is already live (its coordinator or fusion center answers).
//
// Until the first episode starts it also counts the sensors that are ready (their status
// names a schedule version, as the coordinator counts them) and says so at most once a second
// when the count changed: "ready 143/200 sensors (4.2 s)".
//
//   ProgressWatcher progress(run.domainConfig(), 20, scenario.horizon_s, scenario.sensorCount());
//   if (progress.seesLiveRun(500ms)) refuse();       // before starting any process
//   progress.poll(std::chrono::milliseconds(50));   // prints the episodes reported meanwhile
//   // [3/20] episode 2: realized 12.3, running mean 11.8 ± 0.9 (95%), bracket [10.2, 30.1]
//   RunPosition at = progress.positionAt(wallNowNs());   // episode 3, emulated time 1.25 s

#include <chrono>
#include <cstdint>
#include <optional>
#include <set>
#include <string>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/emulator/episode_set.hpp"
#include "sensornet/emulator/run_inputs.hpp"
#include "sensornet/launcher/fault.hpp"  // RunPosition

namespace sensornet::launcher {

// The progress line of one episode's report.
[[nodiscard]] std::string formatProgress(const sensornet_Report& report, int episodes_planned);

class ProgressWatcher {
 public:
  ProgressWatcher(const dds::DomainConfig& config, int episodes_planned, double horizon_s,
                  int sensor_count);

  // True if, within `wait`, a writer of the run's Scenario or Report topic matches: a
  // coordinator or fusion center of this run id is alive in this domain and partition. Returns
  // as soon as one matches. Call it before starting the run's own processes.
  [[nodiscard]] bool seesLiveRun(std::chrono::milliseconds wait) const;

  // Waits up to `wait` for reports and episode controls; prints a line for each episode not
  // printed yet.
  void poll(std::chrono::milliseconds wait);
  [[nodiscard]] std::size_t episodesSeen() const noexcept { return printed_.size(); }
  [[nodiscard]] RunPosition positionAt(std::int64_t wall_ns) const;
  // Its participant in the run's domain and partition, for other launcher entities of the run.
  [[nodiscard]] const dds::Participant& participant() const noexcept { return participant_; }

 private:
  void takeControls();
  void takeStatuses();
  void sayAllReady();
  void sayReady(std::size_t count);

  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Report> topic_;
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Reader<sensornet_Report> reader_;
  dds::Reader<sensornet_Scenario> scenario_reader_;
  dds::Reader<sensornet_EpisodeControl> control_reader_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Reader<sensornet_SensorStatus> status_reader_;
  dds::ReadCondition has_data_;
  dds::ReadCondition has_control_;
  dds::WaitSet waitset_;
  int episodes_planned_;
  double horizon_s_;
  int sensor_count_;
  std::set<std::uint32_t> ready_;  // sensors ready before the first episode
  std::size_t ready_said_ = 0;     // the count last printed
  std::chrono::steady_clock::time_point created_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point ready_said_at_{};
  emulator::EpisodeSet printed_;  // as ranges: small over millions of episodes
  std::optional<std::uint32_t> episode_;  // the latest episode announced
  emulator::EpisodeClock clock_;          // its clock
  // The one announced before it: it still runs while the latest (announced ahead) waits.
  std::optional<std::uint32_t> previous_episode_;
  emulator::EpisodeClock previous_clock_;
  bool shut_down_ = false;
};

}  // namespace sensornet::launcher
