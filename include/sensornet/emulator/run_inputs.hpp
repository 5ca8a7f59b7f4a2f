#pragma once
// What the sensor agents and the fusion center follow of a run: the scenario (once), the
// schedule versions (stale and malformed ones refused, counted and logged) and the episode
// controls. An episode start that overtook the scenario or its schedule versions (they travel on
// other topics) is held back until the scenario and the version the start names (the one in
// force at the episode's start, and so every version before it) are there; a repeated start
// (durability replays the last ones to a late joiner) is dropped. A start may come well before
// its start time (the coordinator announces the next episode while the current one runs).
//
//   RunInputs inputs(participant);
//   inputs.attachTo(waitset);                    // wakes the wait on any of the three topics
//   const RunInputs::Update u = inputs.poll();   // after every wait
//   if (u.scenario_arrived) ...;                 // inputs.run(), inputs.plant() are set
//   for (const EpisodeStart& s : u.starts) ...;  // in order, each episode once
//   if (u.shutdown) ...;

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/emulator/episode_controls.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {

// What RunInputs decides, free of DDS: it takes the three topics' samples one at a time (from
// RunInputs' readers, or from a recording, `sensornet replay`) and says what they mean.
class RunInputState {
 public:
  struct Update {
    bool scenario_arrived = false;
    std::size_t new_versions = 0;  // the last new_versions entries of book().versions()
    std::vector<EpisodeStart> starts;
    std::vector<std::uint32_t> stops;
    std::vector<SensorFailure> failures;
    bool shutdown = false;
    RunEnd end;  // when shutdown
  };

  void onScenario(const sensornet_Scenario& sample, Update& update);
  void onSchedule(const sensornet_Schedule& sample, Update& update);
  void onControl(const sensornet_EpisodeControl& sample, Update& update);
  // Releases the starts held back until the scenario and the versions they name are there.
  void releaseStarts(Update& update);

  [[nodiscard]] bool hasScenario() const { return run_.has_value(); }
  [[nodiscard]] const RunScenario& run() const { return *run_; }
  [[nodiscard]] const Scenario& scenario() const { return run_->scenario; }
  [[nodiscard]] const EmulatedPlant& plant() const { return *plant_; }
  [[nodiscard]] const ScheduleBook& book() const { return book_; }
  [[nodiscard]] std::optional<std::uint32_t> lastStarted() const { return last_started_; }
  [[nodiscard]] const std::set<int>& failedSensors() const { return failed_sensors_; }
  [[nodiscard]] const std::map<std::string, std::uint64_t>& rejected() const { return rejected_; }

 private:
  void reject(RejectionReason reason) { ++rejected_[std::string(wordOf(reason))]; }
  std::optional<RunScenario> run_;
  std::optional<EmulatedPlant> plant_;
  ScheduleBook book_;
  struct HeldStart {
    EpisodeStart start;
    std::uint64_t seed = 0;               // must be the run's
    std::uint32_t schedule_version = 0;   // the book must hold it before the start goes out
  };
  std::vector<HeldStart> held_starts_;
  std::optional<std::uint32_t> last_started_;
  std::set<int> failed_sensors_;
  std::map<std::string, std::uint64_t> rejected_;
};

class RunInputs {
 public:
  using Update = RunInputState::Update;

  explicit RunInputs(const dds::Participant& participant);

  // Attaches the three topics' read conditions with the tokens kScenarioToken.. + 2.
  void attachTo(dds::WaitSet& waitset);
  static constexpr dds_attach_t kScenarioToken = 1001;

  // Takes what arrived on the three topics.
  [[nodiscard]] Update poll();

  [[nodiscard]] const RunInputState& state() const { return state_; }
  [[nodiscard]] bool hasScenario() const { return state_.hasScenario(); }
  [[nodiscard]] const RunScenario& run() const { return state_.run(); }
  [[nodiscard]] const Scenario& scenario() const { return state_.scenario(); }
  [[nodiscard]] const EmulatedPlant& plant() const { return state_.plant(); }
  [[nodiscard]] const ScheduleBook& book() const { return state_.book(); }
  // The last episode handed out in Update::starts.
  [[nodiscard]] std::optional<std::uint32_t> lastStarted() const { return state_.lastStarted(); }
  // Every sensor the coordinator has said is dead (from starts and failure notices).
  [[nodiscard]] const std::set<int>& failedSensors() const { return state_.failedSensors(); }
  // True once the EpisodeControl reader matched a writer (the coordinator's): before that an
  // episode's announcement may be missed, since a late joiner gets only the latest control.
  [[nodiscard]] bool controlMatched() const { return control_reader_.matchedWriters() > 0; }
  // Samples refused, by reason: malformed scenario or schedule, stale schedule, bad episode
  // control.
  [[nodiscard]] const std::map<std::string, std::uint64_t>& rejected() const {
    return state_.rejected();
  }

 private:
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Reader<sensornet_Scenario> scenario_reader_;
  dds::Reader<sensornet_Schedule> schedule_reader_;
  dds::Reader<sensornet_EpisodeControl> control_reader_;
  dds::ReadCondition scenario_ready_;
  dds::ReadCondition schedule_ready_;
  dds::ReadCondition control_ready_;
  RunInputState state_;
};

}  // namespace sensornet::emulator
