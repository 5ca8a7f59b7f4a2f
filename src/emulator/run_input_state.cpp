#include "sensornet/emulator/run_input_state.hpp"

#include <spdlog/spdlog.h>

#include "sensornet/core/input_error.hpp"

namespace sensornet::emulator {

void RunInputState::reject(RejectionReason reason, std::string_view detail) {
  ++rejected_[std::string(wordOf(reason))];
  spdlog::warn("refused a sample ({}): {}", wordOf(reason), detail);
}

void RunInputState::onScenario(RunScenario run, Update& update) {
  if (run_) return;  // one scenario per run
  try {
    plant_.emplace(run.scenario, run.seed);
  } catch (const InputError& error) {
    reject(RejectionReason::MalformedScenario, error.what());
    return;
  }
  run_ = std::move(run);
  update.scenario_arrived = true;
  spdlog::info("scenario {} received: n = {}, M = {}, T = {} s", run_->digest,
               run_->scenario.stateDim(), run_->scenario.sensorCount(), run_->scenario.horizon_s);
}

void RunInputState::onSchedule(ScheduleVersion version, Update& update) {
  if (!run_) return;  // the caller holds it until the scenario is known
  const auto number = version.version;
  const ScheduleBook::Outcome outcome = book_.add(std::move(version));
  if (outcome == ScheduleBook::Outcome::Duplicate) return;  // a restarted coordinator's
  if (outcome == ScheduleBook::Outcome::Stale) {
    reject(RejectionReason::StaleSchedule, "schedule version " + std::to_string(number) +
                                               " is older than version " +
                                               std::to_string(book_.latest().version));
    return;
  }
  ++update.new_versions;
  spdlog::info("schedule version {} ({}) from episode {} at {} s", number,
               wordOf(book_.latest().surrogate), book_.latest().effective_episode,
               book_.latest().effective_time_s);
}

void RunInputState::onControl(const EpisodeControl& c, Update& update) {
  const std::set<int> sensors(c.failed_sensors.begin(), c.failed_sensors.end());
  switch (c.kind) {
    case ControlKind::RunShutdown:
      update.shutdown = true;
      update.end = {c.episodes_planned, c.aborted, c.detail};
      break;
    case ControlKind::EpisodeStop:
      update.stops.push_back(c.episode);
      break;
    case ControlKind::EpisodeStart:
      held_starts_.push_back(
          {{c.episode, {c.start_wall_ns, c.time_scale}, c.episodes_planned, sensors},
           c.seed,
           c.schedule_version});
      break;
    case ControlKind::SensorsFailed:
      failed_sensors_.insert(sensors.begin(), sensors.end());
      update.failures.push_back({c.episode, c.failed_at_s, sensors, c.detail});
      break;
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
      reject(RejectionReason::MalformedEpisodeControl,
             "episode " + std::to_string(s.episode) + "'s start has a bad time scale or seed");
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
