#pragma once
// What a sensor agent decides, without DDS or a clock of its own (docs/ARCHITECTURE.md,
// "Cores"): which of its sensors are alive, when each episode starts for it, which measurement
// falls due when and what the emulated network does to it, when a scripted crash comes, what
// each tally and status says, how far it fell behind the emulated clock (its own stalls and a
// start the network delivered late left out) and when it leaves the run. Events go in (what
// RunInputState made of the run's topics, the writers' discovery, a write that timed out, a stop
// signal, tick(now)); the actions to carry out, in order, come out:
//
//   SensorAgentCore core(config, inputs.state());
//   carryOut(core.start(now()));
//   while (!core.exitCode()) {
//     waitset.wait(core.untilNextEvent(now()));
//     core.onDiscovery({...});
//     carryOut(core.onInputs(inputs.poll(), now()));
//     carryOut(core.tick(now()));
//   }
//
// The measurements are drawn here (EmulatedPlant, keyed by the run seed), so a test sees the
// same values a run publishes. How late a measurement goes out is measured at the tick that
// hands it out: a block of measurements handed out together counts from the same `now`.

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "sensornet/emulator/episode_controls.hpp"
#include "sensornet/emulator/log_line.hpp"
#include "sensornet/emulator/network_emulation.hpp"
#include "sensornet/emulator/run_input_state.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/emulator/stall_watch.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {

struct SensorAgentConfig {
  std::vector<int> sensors;      // the hosted sensors, as --sensors lists them
  double status_period_s = 1.0;  // a SensorStatus at least this often
};

// What the agent's writers and reader have matched (its readiness needs all three).
struct AgentDiscovery {
  bool control_matched = false;      // its EpisodeControl reader, with the coordinator's writer
  bool measurement_matched = false;  // its Measurement writer, with a reader
  bool tally_matched = false;        // its EpisodeTally writer, with a reader
};

// Actions, to carry out in the order given.
struct PublishMeasurement {
  std::uint32_t episode = 0;
  HeldMeasurement measurement;
};
struct PublishTally {
  std::uint32_t episode = 0;
  int sensor = 0;
  std::uint64_t sent = 0;
  std::uint64_t dropped_by_network = 0;
  std::uint64_t duplicated_by_network = 0;
  bool finished = true;  // ran to T (false: stopped early)
  std::uint64_t write_timeouts = 0;
  double max_lag_s = 0.0;
  double stalled_s = 0.0;
  std::int64_t wall_time_ns = 0;
};
struct PublishSensorStatus {
  int sensor = 0;
  SensorState state = SensorState::Starting;
  std::uint32_t episode = 0;
  std::uint32_t schedule_version = 0;
  double current_rate_hz = 0.0;
  std::uint64_t sent_in_episode = 0;
  std::uint64_t sent_total = 0;
  std::uint64_t write_timeouts = 0;
  std::int64_t wall_time_ns = 0;
  std::string detail;
};
// The scenario's scripted crash: die now like kill -9 (no clean DDS exit, no tally).
struct CrashProcess {};
// Leave the run with this exit code; `flush`: first wait (a few seconds at most) until what was
// written is acknowledged.
struct LeaveRun {
  int exit_code = 0;
  bool flush = true;
};

using SensorAgentAction =
    std::variant<PublishMeasurement, PublishTally, PublishSensorStatus, LogLine, CrashProcess,
                 LeaveRun>;
using SensorAgentActions = std::vector<SensorAgentAction>;

class SensorAgentCore {
 public:
  // `inputs` is what the executable's RunInputs (or a test) made of the run's topics; the core
  // reads the scenario, the plant, the schedule book and the failed sensors from it.
  SensorAgentCore(SensorAgentConfig config, const RunInputState& inputs);

  // The first status: starting, waiting for scenario and schedule.
  [[nodiscard]] SensorAgentActions start(std::int64_t now);
  // What RunInputState made of the samples just taken. Throws InputError when the scenario
  // has fewer sensors than this agent hosts.
  [[nodiscard]] SensorAgentActions onInputs(const RunInputState::Update& update, std::int64_t now);
  void onDiscovery(const AgentDiscovery& discovery) { discovery_ = discovery; }
  // A reliable write timed out and is being retried (the reader lags): counted, and the time it
  // spent blocked is work, not a stall of this process.
  void onWriteTimeout(std::int64_t now);
  // SIGINT/SIGTERM: the last status, then leave without waiting.
  [[nodiscard]] SensorAgentActions onStopSignal(std::int64_t now);
  // Publishes what fell due, ends and starts episodes, republishes the status when it changed
  // or its period came.
  [[nodiscard]] SensorAgentActions tick(std::int64_t now);

  // Until the next arrival, held-back measurement, scripted crash or the episode's end falls
  // due, at most `idle`.
  [[nodiscard]] std::chrono::nanoseconds untilNextEvent(std::int64_t now,
                                                        std::chrono::nanoseconds idle) const;
  // Set once a LeaveRun or CrashProcess was handed out.
  [[nodiscard]] std::optional<int> exitCode() const { return exit_code_; }
  [[nodiscard]] SensorState state() const;
  [[nodiscard]] const std::vector<int>& liveSensors() const { return live_sensors_; }

 private:
  struct ScriptedCrash {
    int sensor = 0;
    double at_s = 0.0;
  };
  struct Episode {
    std::uint32_t number = 0;
    EpisodeClock clock;
    std::vector<TimedArrival> timeline;
    std::size_t next = 0;  // first arrival not yet handed out
    EmulatedPlant::Path plant_path;  // the timeline is sorted: each state starts from the last
    double last_published_s = -1.0;
    std::map<int, std::uint64_t> sent;  // per live hosted sensor: every drawn arrival (its seq)
    std::map<int, std::uint64_t> dropped_by_network;     // of sent: never written
    std::map<int, std::uint64_t> duplicated_by_network;  // of sent: written twice
    DelayLine held;  // delayed by the emulated network, not yet written
    std::optional<ScriptedCrash> crash;
    double max_lag_s = 0.0;
    // When its start reached this process: nothing is due before (a start the network
    // delivered late is the network's delay, not this sensor falling behind).
    std::int64_t known_from_ns = 0;
    std::uint64_t write_timeouts_at_start = 0;
  };
  struct Announced {
    EpisodeStart start;
    std::int64_t learned_ns = 0;
  };

  void noteOwnStall(std::int64_t now, SensorAgentActions& out);
  void onNewVersion(std::uint32_t episode, double at, SensorAgentActions& out);
  [[nodiscard]] std::vector<TimedArrival> timelineOf(std::uint32_t episode) const;
  void noteFailedSensors(const std::set<int>& failed, SensorAgentActions& out);
  [[nodiscard]] std::optional<ScriptedCrash> crashIn(std::uint32_t episode) const;
  void startNextEpisode(std::int64_t now, SensorAgentActions& out);
  void publishDue(std::int64_t now, SensorAgentActions& out);
  void transmit(Episode& e, const TimedArrival& a, SensorAgentActions& out);
  static void writeHeld(const Episode& e, std::vector<HeldMeasurement> due,
                        SensorAgentActions& out);
  [[nodiscard]] bool crashIfDue(Episode& e, double time_s, SensorAgentActions& out);
  void noteLag(Episode& e, double time_s, std::int64_t now);
  void finishEpisode(const std::string& why, std::int64_t now, SensorAgentActions& out);
  void publishStatus(SensorState state, const std::string& detail, std::int64_t now,
                     SensorAgentActions& out);

  SensorAgentConfig config_;
  const RunInputState& inputs_;
  AgentDiscovery discovery_;
  StallWatch stall_watch_;
  std::optional<Episode> episode_;
  std::deque<Announced> pending_;  // announced, to run after the current one
  std::vector<int> live_sensors_;
  const NetworkSpec* network_ = nullptr;  // the scenario's, when it impairs anything
  std::uint64_t sent_total_ = 0;
  std::uint64_t write_timeouts_ = 0;
  std::int64_t next_status_ns_ = 0;
  SensorState last_state_ = SensorState::Starting;
  std::optional<int> exit_code_;
};

}  // namespace sensornet::emulator
