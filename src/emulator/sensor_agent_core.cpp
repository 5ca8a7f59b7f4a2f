#include "sensornet/emulator/sensor_agent_core.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/command_line.hpp"

namespace sensornet::emulator {
namespace {

// In place: GCC 12 takes a moved-from temporary variant for uninitialized (maybe-uninitialized).
template <class A>
void act(SensorAgentActions& out, A action) {
  out.emplace_back(std::in_place_type<A>, std::move(action));
}

}  // namespace

SensorAgentCore::SensorAgentCore(SensorAgentConfig config, const RunInputState& inputs)
    : config_(std::move(config)), inputs_(inputs), live_sensors_(config_.sensors) {}

SensorAgentActions SensorAgentCore::start(std::int64_t now) {
  SensorAgentActions out;
  stall_watch_.busyUntil(now);
  publishStatus(SensorState::Starting, "waiting for scenario and schedule", now, out);
  return out;
}

void SensorAgentCore::noteOwnStall(std::int64_t now, SensorAgentActions& out) {
  if (const auto stall = stall_watch_.tick(now)) {
    act(out, LogLine{spdlog::level::warn,
                          fmt::format("this sensor agent was stalled for {:.3g} s",
                                      stall->seconds())});
  }
}

void SensorAgentCore::onWriteTimeout(std::int64_t now) {
  ++write_timeouts_;
  stall_watch_.busyUntil(now);
}

SensorAgentActions SensorAgentCore::onInputs(const RunInputState::Update& update,
                                             std::int64_t now) {
  SensorAgentActions out;
  if (exit_code_) return out;
  noteOwnStall(now, out);
  if (update.scenario_arrived) {
    for (const int id : config_.sensors) {
      if (id >= inputs_.scenario().sensorCount()) {
        throw InputError("--sensors", "sensors",
                         "ids below the scenario's M = " +
                             std::to_string(inputs_.scenario().sensorCount()) + ", got " +
                             std::to_string(id));
      }
    }
    const auto& network = inputs_.scenario().network;
    network_ = network && impairs(*network) ? &*network : nullptr;
  }
  const auto& versions = inputs_.book().versions();
  for (auto v = versions.end() - static_cast<std::ptrdiff_t>(update.new_versions);
       v != versions.end(); ++v) {
    onNewVersion(v->effective_episode, v->effective_time_s, out);
  }
  if (update.new_versions > 0) publishStatus(state(), "", now, out);
  for (const std::uint32_t episode : update.stops) {
    if (episode_ && episode_->number == episode) finishEpisode("stopped", now, out);
    std::erase_if(pending_, [&](const Announced& a) { return a.start.episode == episode; });
  }
  // The next episode is announced while this one runs: it starts once this one is finished.
  for (const EpisodeStart& start : update.starts) pending_.push_back({start, now});
  if (update.shutdown) {
    publishStatus(SensorState::Stopped, "run shut down", now, out);
    act(out, LeaveRun{kExitOk, true});
    exit_code_ = kExitOk;
  }
  return out;
}

SensorAgentActions SensorAgentCore::onStopSignal(std::int64_t now) {
  SensorAgentActions out;
  if (exit_code_) return out;
  publishStatus(SensorState::Stopped, "stopped by a signal", now, out);
  act(out, LeaveRun{kExitFailure, false});
  exit_code_ = kExitFailure;
  return out;
}

SensorAgentActions SensorAgentCore::tick(std::int64_t now) {
  SensorAgentActions out;
  if (exit_code_) return out;
  noteOwnStall(now, out);
  if (episode_) publishDue(now, out);
  if (exit_code_) return out;  // crashed
  if (!episode_ && !pending_.empty()) {
    startNextEpisode(now, out);
    publishDue(now, out);  // what is already due (a start that came late) goes out now
    if (exit_code_) return out;
  }
  const SensorState current = state();
  if (now >= next_status_ns_ || current != last_state_) publishStatus(current, "", now, out);
  return out;
}

std::chrono::nanoseconds SensorAgentCore::untilNextEvent(std::int64_t now,
                                                         std::chrono::nanoseconds idle) const {
  if (!episode_) return idle;
  const Episode& e = *episode_;
  std::int64_t due_ns = now + idle.count();
  if (e.next < e.timeline.size()) {
    due_ns = std::min(due_ns, e.clock.wallAt(e.timeline[e.next].time_s));
  } else {
    due_ns = std::min(due_ns, e.clock.wallAt(inputs_.scenario().horizon_s));
  }
  if (const auto held = e.held.nextDueWallNs()) due_ns = std::min(due_ns, *held);
  if (e.crash) due_ns = std::min(due_ns, e.clock.wallAt(e.crash->at_s));
  return std::clamp(std::chrono::nanoseconds(due_ns - now), std::chrono::nanoseconds(0), idle);
}

// Re-plans the rest of the current episode; what was already published is unchanged.
void SensorAgentCore::onNewVersion(std::uint32_t episode, double at, SensorAgentActions& out) {
  if (!episode_ || episode != episode_->number) return;
  Episode& e = *episode_;
  if (at < e.last_published_s) {
    act(out, LogLine{spdlog::level::warn,
                          fmt::format("schedule switch at {} s arrived after {} s was already "
                                      "published",
                                      at, e.last_published_s)});
  }
  e.timeline = timelineOf(e.number);
  e.next = static_cast<std::size_t>(
      std::upper_bound(e.timeline.begin(), e.timeline.end(), e.last_published_s,
                       [](double t, const TimedArrival& a) { return t < a.time_s; }) -
      e.timeline.begin());
}

std::vector<TimedArrival> SensorAgentCore::timelineOf(std::uint32_t episode) const {
  return sensorTimeline(inputs_.book(), inputs_.plant(), inputs_.run().seed, episode,
                        live_sensors_, inputs_.scenario().horizon_s,
                        inputs_.scenario().arrivals);
}

// The hosted sensors the coordinator has not declared dead (they publish nothing, no tally).
void SensorAgentCore::noteFailedSensors(const std::set<int>& failed, SensorAgentActions& out) {
  live_sensors_.clear();
  for (const int id : config_.sensors) {
    if (failed.count(id) == 0) {
      live_sensors_.push_back(id);
    } else {
      act(out, LogLine{spdlog::level::warn,
                            fmt::format("sensor {} was declared failed: it publishes nothing more",
                                        id)});
    }
  }
}

// The earliest scripted crash of a live hosted sensor in `episode`.
std::optional<SensorAgentCore::ScriptedCrash> SensorAgentCore::crashIn(
    std::uint32_t episode) const {
  std::optional<ScriptedCrash> first;
  for (const CrashFault& fault : inputs_.scenario().faults) {
    const bool hosted = std::find(live_sensors_.begin(), live_sensors_.end(), fault.sensor) !=
                        live_sensors_.end();
    if (hosted && fault.episode == episode && (!first || fault.at_s < first->at_s)) {
      first = ScriptedCrash{fault.sensor, fault.at_s};
    }
  }
  return first;
}

// The episode announced next: its timeline is drawn now (its clock may not have started yet;
// nothing is published before its arrivals fall due). A version that arrives before its start
// and takes effect in it redraws the timeline (onNewVersion).
void SensorAgentCore::startNextEpisode(std::int64_t now, SensorAgentActions& out) {
  const EpisodeStart start = pending_.front().start;
  const std::int64_t learned_ns = pending_.front().learned_ns;
  pending_.pop_front();
  std::set<int> failed = start.failed_sensors;  // and those a notice named since
  failed.insert(inputs_.failedSensors().begin(), inputs_.failedSensors().end());
  noteFailedSensors(failed, out);
  Episode e;
  e.number = start.episode;
  e.clock = start.clock;
  e.timeline = timelineOf(start.episode);
  for (const int id : live_sensors_) e.sent[id] = 0;
  e.crash = crashIn(start.episode);
  e.write_timeouts_at_start = write_timeouts_;
  e.known_from_ns = learned_ns;
  if (const double late_s = 1e-9 * static_cast<double>(learned_ns - e.clock.wallAt(0.0));
      late_s > 0.1) {
    act(out, LogLine{spdlog::level::warn,
                          fmt::format("episode {}: its start reached this process {:.3f} s after "
                                      "it began (the network's delay; what fell due meanwhile "
                                      "goes out now)",
                                      e.number, late_s)});
  }
  episode_ = std::move(e);
  publishStatus(SensorState::Running, "", now, out);
}

void SensorAgentCore::publishDue(std::int64_t now, SensorAgentActions& out) {
  Episode& e = *episode_;
  const double emulated_now = e.clock.emulatedAt(now);
  while (e.next < e.timeline.size() && e.timeline[e.next].time_s <= emulated_now) {
    const TimedArrival& a = e.timeline[e.next];
    if (crashIfDue(e, a.time_s, out)) return;  // a crash at or before this arrival comes first
    transmit(e, a, out);
    noteLag(e, a.time_s, now);
    e.last_published_s = a.time_s;
    ++e.next;
    ++sent_total_;
  }
  if (crashIfDue(e, emulated_now, out)) return;
  writeHeld(e, e.held.takeDue(now), out);
  if (emulated_now >= inputs_.scenario().horizon_s && e.next >= e.timeline.size() &&
      e.held.empty()) {
    finishEpisode("", now, out);
  }
}

// One drawn arrival through the emulated network: it takes its seq whatever happens to it;
// dropped, it is only counted; delayed, it waits in the delay line; otherwise it is written now
// (twice when duplicated). Without a network it is written now, as always.
void SensorAgentCore::transmit(Episode& e, const TimedArrival& a, SensorAgentActions& out) {
  const std::uint64_t seq = e.sent[a.sensor]++;
  const NetworkDecision fate =
      network_ != nullptr
          ? decideDelivery(*network_, inputs_.run().seed, a.sensor, e.number, seq, a.time_s)
          : NetworkDecision{};
  if (fate.dropped()) {
    ++e.dropped_by_network[a.sensor];
    return;
  }
  const EmulatedPlant& plant = inputs_.plant();
  const Eigen::VectorXd& x = plant.stateAt(e.number, a.tick, e.plant_path);
  HeldMeasurement m{a.sensor, seq, a.time_s, a.version, plant.measure(x, a.sensor, e.number, seq),
                    fate.delay_s};
  const int copies = fate.duplicated ? 2 : 1;
  if (fate.duplicated) ++e.duplicated_by_network[a.sensor];
  if (fate.delay_s > 0.0) {
    e.held.hold(e.clock.wallAt(a.time_s + fate.delay_s), std::move(m), copies);
    return;
  }
  for (int copy = 1; copy < copies; ++copy) act(out, PublishMeasurement{e.number, m});
  act(out, PublishMeasurement{e.number, std::move(m)});
}

void SensorAgentCore::writeHeld(const Episode& e, std::vector<HeldMeasurement> due,
                                SensorAgentActions& out) {
  for (HeldMeasurement& m : due) act(out, PublishMeasurement{e.number, std::move(m)});
}

// The scenario's scripted crash, once its instant has come by `time_s`: what the network held
// until then goes out, one line is logged, and the process dies like kill -9.
bool SensorAgentCore::crashIfDue(Episode& e, double time_s, SensorAgentActions& out) {
  if (!e.crash || e.crash->at_s > time_s) return false;
  writeHeld(e, e.held.takeDue(e.clock.wallAt(e.crash->at_s)), out);
  act(out, LogLine{spdlog::level::err,
                        fmt::format("scripted crash of sensor {} at {} s of episode {}",
                                    e.crash->sensor, e.crash->at_s, e.number)});
  act(out, CrashProcess{});
  exit_code_ = kExitFailure;
  return true;
}

// How far behind the emulated clock a measurement went out, leaving out the time this process
// was stalled since it fell due (a stall is not overload) and the time before its episode's
// start reached it (the network's delay, not this process falling behind).
void SensorAgentCore::noteLag(Episode& e, double time_s, std::int64_t now) {
  const std::int64_t due = std::max(e.clock.wallAt(time_s), e.known_from_ns);
  if (now <= due) return;
  const double lag = 1e-9 * static_cast<double>(now - due) - stall_watch_.stalledBetween(due, now);
  e.max_lag_s = std::max(e.max_lag_s, lag);
}

// Each hosted sensor's tally of the episode (`why` empty: it ran to T).
void SensorAgentCore::finishEpisode(const std::string& why, std::int64_t now,
                                    SensorAgentActions& out) {
  Episode& e = *episode_;
  if (!e.held.empty()) {  // ended early: what the network still held goes out now
    act(out, LogLine{spdlog::level::info,
                          fmt::format("episode {}: writing {} measurements the network still held",
                                      e.number, e.held.size())});
    writeHeld(e, e.held.takeAll(), out);
  }
  const double stalled_s = stall_watch_.stalledBetween(e.clock.start_wall_ns, now);
  for (const auto& [sensor, count] : e.sent) {
    PublishTally t;
    t.episode = e.number;
    t.sensor = sensor;
    t.sent = count;
    t.dropped_by_network = e.dropped_by_network[sensor];
    t.duplicated_by_network = e.duplicated_by_network[sensor];
    t.finished = why.empty();
    t.write_timeouts = write_timeouts_ - e.write_timeouts_at_start;
    t.max_lag_s = e.max_lag_s;
    t.stalled_s = stalled_s;
    t.wall_time_ns = now;
    act(out, t);
  }
  if (!why.empty()) {
    act(out, LogLine{spdlog::level::info,
                          fmt::format("episode {} ended early: {}", e.number, why)});
  }
  stall_watch_.forgetBefore(e.clock.start_wall_ns);
  episode_.reset();
  if (pending_.empty()) publishStatus(SensorState::Ready, "", now, out);  // else running on
}

// Ready once it has the scenario and a schedule, its measurement and tally writers have matched
// a reader (the fusion center's): a measurement written before the match would not reach a
// volatile reader, and its episode-control reader has matched the coordinator's writer: a
// reader that matches late gets only the latest announcement. (On a lossy link discovery can
// lag the scenario by seconds, and endpoints are announced one by one.)
SensorState SensorAgentCore::state() const {
  if (episode_) return SensorState::Running;
  if (inputs_.hasScenario() && !inputs_.book().empty() && discovery_.control_matched &&
      discovery_.measurement_matched && discovery_.tally_matched) {
    return SensorState::Ready;
  }
  return SensorState::Starting;
}

void SensorAgentCore::publishStatus(SensorState state, const std::string& detail,
                                    std::int64_t now, SensorAgentActions& out) {
  last_state_ = state;
  next_status_ns_ = now + static_cast<std::int64_t>(1e9 * config_.status_period_s);
  // The version in force now, or between episodes the one the next episode starts with (the
  // same for every hosted sensor).
  const std::optional<std::uint32_t> last = inputs_.lastStarted();
  const std::uint32_t episode = episode_ ? episode_->number : last.value_or(0);
  const std::uint32_t in_force_episode = episode_ ? episode : (last ? *last + 1 : 0);
  const ScheduleVersion* v = nullptr;
  double t = 0.0;
  if (inputs_.hasScenario() && !inputs_.book().empty()) {
    if (episode_) {
      t = std::clamp(episode_->clock.emulatedAt(now), 0.0, inputs_.scenario().horizon_s);
    }
    v = inputs_.book().inForce(in_force_episode, t);
  }
  for (const int id : config_.sensors) {
    // Excluded: the version in force gives it no rate at all, from where the version took
    // effect (a sensor a plan merely leaves idle late in an episode is still running).
    bool excluded_by_version = false;
    if (v != nullptr) {
      const RateSchedule& schedule = v->schedule;
      const int first = v->effective_episode == in_force_episode
                            ? schedule.intervalAt(v->effective_time_s)
                            : 0;
      excluded_by_version = schedule.rates().col(id).tail(schedule.intervals() - first).isZero();
    }
    const bool live = state == SensorState::Ready || state == SensorState::Running;
    PublishSensorStatus s;
    s.sensor = id;
    s.state = live && excluded_by_version ? SensorState::Excluded : state;
    s.episode = episode;
    s.schedule_version = v != nullptr ? v->version : 0;
    s.current_rate_hz = v != nullptr ? v->schedule.rateAt(t, id) : 0.0;
    const bool counted = episode_ && episode_->sent.count(id) > 0;
    s.sent_in_episode = counted ? episode_->sent.at(id) : 0;
    s.sent_total = sent_total_;
    s.write_timeouts = write_timeouts_;
    s.wall_time_ns = now;
    s.detail = detail;
    act(out, std::move(s));
  }
}

}  // namespace sensornet::emulator
