#pragma once
// The three topics the sensor agents and the fusion center follow of a run (Scenario, Schedule,
// EpisodeControl), read off DDS and decoded into RunInputState (emulator/run_input_state.hpp),
// which decides what they mean. A sample that does not decode is refused there, counted by
// reason and logged; the run goes on.
//
//   RunInputs inputs(participant);
//   inputs.attachTo(waitset);                    // wakes the wait on any of the three topics
//   const RunInputs::Update u = inputs.poll();   // after every wait
//   if (u.scenario_arrived) ...;                 // inputs.run(), inputs.plant() are set
//   for (const EpisodeStart& s : u.starts) ...;  // in order, each episode once
//   if (u.shutdown) ...;
//
// A recording's samples, or a test's, go the same way without DDS: feedSample(state, sample,
// update) for each, then state.releaseStarts(update).

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "sensornet/dds/matched_endpoints.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/emulator/run_input_state.hpp"

namespace sensornet::wire {

using emulator::RunInputState;

// Decodes a sample and hands it to `state`, or has `state` refuse it (reject) when it does not
// decode. A schedule sample before the scenario is ignored: RunInputs keeps those in the reader
// until the scenario is known.
void feedSample(RunInputState& state, const sensornet_Scenario& sample,
                RunInputState::Update& update);
void feedSample(RunInputState& state, const sensornet_Schedule& sample,
                RunInputState::Update& update);
void feedSample(RunInputState& state, const sensornet_EpisodeControl& sample,
                RunInputState::Update& update);

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
  [[nodiscard]] const emulator::RunScenario& run() const { return state_.run(); }
  [[nodiscard]] const Scenario& scenario() const { return state_.scenario(); }
  [[nodiscard]] const EmulatedPlant& plant() const { return state_.plant(); }
  [[nodiscard]] const emulator::ScheduleBook& book() const { return state_.book(); }
  // The last episode handed out in Update::starts.
  [[nodiscard]] std::optional<std::uint32_t> lastStarted() const { return state_.lastStarted(); }
  // Every sensor the coordinator has said is dead (from starts and failure notices).
  [[nodiscard]] const std::set<int>& failedSensors() const { return state_.failedSensors(); }
  // True once the EpisodeControl reader matched a writer (the coordinator's): before that an
  // episode's announcement may be missed, since a late joiner gets only the latest control.
  [[nodiscard]] bool controlMatched() const { return control_reader_.matchedWriters() > 0; }
  // How many coordinator processes (participants) have had their EpisodeControl writer matched
  // with this reader so far: more than one means the coordinator was restarted (or replaced)
  // while the run went on. Cheap when nothing changed: call it every turn.
  [[nodiscard]] std::size_t coordinatorProcessesSeen();
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
  dds::MatchedWriterParticipants control_writers_;  // the participants matched now
  std::set<dds::ParticipantKey> coordinators_;     // every one matched so far
  dds::ReadCondition scenario_ready_;
  dds::ReadCondition schedule_ready_;
  dds::ReadCondition control_ready_;
  RunInputState state_;
};

}  // namespace sensornet::wire
