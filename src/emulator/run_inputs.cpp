#include "sensornet/emulator/run_inputs.hpp"

#include <spdlog/spdlog.h>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/wire.hpp"

namespace sensornet::emulator {

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

RunInputs::Update RunInputs::poll() {
  Update update;
  for (auto& received : scenario_reader_.take(4).samples) state_.onScenario(*received.sample, update);
  if (state_.hasScenario()) {  // kept by the reader (transient local) until the scenario is known
    for (auto& received : schedule_reader_.take(32).samples) {
      state_.onSchedule(*received.sample, update);
    }
  }
  for (auto& received : control_reader_.take(16).samples) state_.onControl(*received.sample, update);
  state_.releaseStarts(update);
  return update;
}

void RunInputState::onScenario(const sensornet_Scenario& sample, Update& update) {
  if (run_) return;  // one scenario per run
  try {
    run_ = scenarioFromWire(sample);
    plant_.emplace(run_->scenario, run_->seed);
    update.scenario_arrived = true;
    spdlog::info("scenario {} received: n = {}, M = {}, T = {} s", run_->digest,
                 run_->scenario.stateDim(), run_->scenario.sensorCount(),
                 run_->scenario.horizon_s);
  } catch (const InputError& error) {
    reject(RejectionReason::MalformedScenario);
    run_.reset();
    spdlog::warn("rejected a scenario sample: {}", error.what());
  }
}

void RunInputState::onSchedule(const sensornet_Schedule& sample, Update& update) {
  if (!run_) return;  // the caller holds it until the scenario is known
  try {
    ScheduleVersion v = scheduleFromWire(sample, run_->scenario, run_->digest);
    const auto number = v.version;
    const ScheduleBook::Outcome outcome = book_.add(std::move(v));
    if (outcome == ScheduleBook::Outcome::Duplicate) return;  // a restarted coordinator's
    if (outcome == ScheduleBook::Outcome::Stale) {
      reject(RejectionReason::StaleSchedule);
      spdlog::warn("refused stale schedule version {} (have {})", number,
                   book_.latest().version);
      return;
    }
    ++update.new_versions;
    spdlog::info("schedule version {} ({}) from episode {} at {} s", number,
                 wordOf(book_.latest().surrogate), book_.latest().effective_episode,
                 book_.latest().effective_time_s);
  } catch (const InputError& error) {
    reject(RejectionReason::MalformedSchedule);
    spdlog::warn("rejected a schedule sample: {}", error.what());
  }
}

void RunInputState::onControl(const sensornet_EpisodeControl& c, Update& update) {
  switch (c.command) {
    case sensornet_RUN_SHUTDOWN:
      update.shutdown = true;
      update.end = {c.episodes_planned, c.aborted, std::string(dds::viewString(c.detail))};
      break;
    case sensornet_EPISODE_STOP:
      update.stops.push_back(c.episode);
      break;
    case sensornet_EPISODE_START: {
      std::set<int> failed;
      for (const std::uint32_t id : dds::viewSequence(c.failed_sensors)) {
        failed.insert(static_cast<int>(id));
      }
      held_starts_.push_back(
          {{c.episode, {c.start_wall_time_ns, c.time_scale}, c.episodes_planned, failed},
           c.seed,
           c.schedule_version});
      break;
    }
    case sensornet_EPISODE_SENSORS_FAILED: {
      SensorFailure failure{c.episode, c.failed_at_s, {}, std::string(dds::viewString(c.detail))};
      for (const std::uint32_t id : dds::viewSequence(c.failed_sensors)) {
        failure.sensors.insert(static_cast<int>(id));
        failed_sensors_.insert(static_cast<int>(id));
      }
      update.failures.push_back(std::move(failure));
      break;
    }
  }
}

// A start waits for the scenario, the schedule in force at the episode's start and the version
// it names (versions arrive in order, so every earlier one is in the book too).
void RunInputState::releaseStarts(Update& update) {
  std::erase_if(held_starts_, [&](const HeldStart& held) {
    const EpisodeStart& s = held.start;
    if (!run_ || book_.inForce(s.episode, 0.0) == nullptr ||
        book_.latest().version < held.schedule_version) {
      return false;
    }
    if (!(s.clock.time_scale > 0.0) || held.seed != run_->seed) {
      reject(RejectionReason::MalformedEpisodeControl);
      spdlog::warn("rejected episode control {}: bad time scale or seed", s.episode);
      return true;
    }
    if (!last_started_ || s.episode > *last_started_) {
      last_started_ = s.episode;
      failed_sensors_.insert(s.failed_sensors.begin(), s.failed_sensors.end());
      update.starts.push_back(s);
    }
    return true;
  });
}

}  // namespace sensornet::emulator
