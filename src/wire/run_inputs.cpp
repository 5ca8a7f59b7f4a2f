#include "sensornet/wire/run_inputs.hpp"

#include "sensornet/core/input_error.hpp"
#include "sensornet/wire/messages.hpp"

namespace sensornet::wire {

using emulator::RejectionReason;

void feedSample(RunInputState& state, const sensornet_Scenario& sample,
                RunInputState::Update& update) {
  if (state.hasScenario()) return;  // one scenario per run: a repeat is not even decoded
  try {
    state.onScenario(scenarioFromWire(sample), update);
  } catch (const InputError& error) {
    state.reject(RejectionReason::MalformedScenario, error.what());
  }
}

void feedSample(RunInputState& state, const sensornet_Schedule& sample,
                RunInputState::Update& update) {
  if (!state.hasScenario()) return;
  try {
    state.onSchedule(scheduleFromWire(sample, state.scenario(), state.run().digest), update);
  } catch (const InputError& error) {
    state.reject(RejectionReason::MalformedSchedule, error.what());
  }
}

void feedSample(RunInputState& state, const sensornet_EpisodeControl& sample,
                RunInputState::Update& update) {
  try {
    state.onControl(controlOf(sample), update);
  } catch (const InputError& error) {
    state.reject(RejectionReason::MalformedEpisodeControl, error.what());
  }
}

RunInputs::RunInputs(const dds::Participant& participant)
    : scenario_topic_(participant),
      schedule_topic_(participant),
      control_topic_(participant),
      scenario_reader_(participant, scenario_topic_),
      schedule_reader_(participant, schedule_topic_),
      control_reader_(participant, control_topic_),
      scenario_ready_(scenario_reader_),
      schedule_ready_(schedule_reader_),
      control_ready_(control_reader_) {}

void RunInputs::attachTo(dds::WaitSet& waitset) {
  waitset.attach(scenario_ready_, kScenarioToken);
  waitset.attach(schedule_ready_, kScenarioToken + 1);
  waitset.attach(control_ready_, kScenarioToken + 2);
}

std::size_t RunInputs::coordinatorProcessesSeen() {
  bool changed = false;
  const std::vector<dds::ParticipantKey>& now = control_writers_.of(control_reader_, &changed);
  if (changed) coordinators_.insert(now.begin(), now.end());
  return coordinators_.size();
}

RunInputs::Update RunInputs::poll() {
  Update update;
  for (auto& received : scenario_reader_.take(4).samples) {
    feedSample(state_, *received.sample, update);
  }
  if (state_.hasScenario()) {  // kept by the reader (transient local) until the scenario is known
    for (auto& received : schedule_reader_.take(32).samples) {
      feedSample(state_, *received.sample, update);
    }
  }
  for (auto& received : control_reader_.take(16).samples) {
    feedSample(state_, *received.sample, update);
  }
  state_.releaseStarts(update);
  return update;
}

}  // namespace sensornet::wire
