#include "sensornet/launcher/supervisor.hpp"

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <optional>

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;

std::string signalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal " + std::to_string(signal);
  }
}

std::string listed(const std::vector<int>& sensors) {
  std::string text;
  for (const int j : sensors) text += (text.empty() ? "" : ", ") + std::to_string(j);
  return text;
}

std::string seconds(std::chrono::milliseconds limit) {
  const long long ms = limit.count();
  return ms % 1000 == 0 ? std::to_string(ms / 1000) : std::to_string(static_cast<double>(ms) / 1e3);
}

std::string seconds3(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", s);
  return text;
}

// "episode 0 at t = 0.66 s", "before the first episode".
std::string positionText(const RunPosition& at) {
  if (!at.episode) return "before the first episode";
  std::string text = "episode " + std::to_string(*at.episode);
  if (at.emulated_time_s) text += " at t = " + seconds3(*at.emulated_time_s) + " s";
  return text;
}

// A death the launcher found only after it had not looked for a while (it was stalled itself)
// happened at some moment since the child was last seen alive, not when it was found: the fault
// is dated by that last sight, and says so (issue 31, finding 4).
std::optional<std::string> lateNotice(const RunPosition& found,
                                      const std::optional<LastSeenAlive>& seen) {
  if (!seen || !(seen->unseen_s > kLateDeathNoticeS)) return std::nullopt;
  return "; died after " + positionText(seen->at) + " (last seen alive then), found dead " +
         seconds3(seen->unseen_s) + " s later, " + positionText(found) +
         " (the launcher was not running in between)";
}

}  // namespace

std::string ChildExit::describe() const {
  if (signal != 0) {
    return "killed by signal " + std::to_string(signal) + " (" + ::strsignal(signal) + ")";
  }
  return "exited with status " + std::to_string(exit_code);
}

Supervisor::Supervisor(SupervisorConfig config, SteadyTime started) : config_(std::move(config)) {
  if (config_.timeout) deadline_ = started + *config_.timeout;
}

std::vector<Action> Supervisor::onChildExit(const ChildExit& exit, const RunPosition& at,
                                            SteadyTime now, std::optional<LastSeenAlive> seen) {
  if (phase_ == Phase::Done) return {};
  if (phase_ == Phase::Stopping || exit.succeeded()) return onChildEnded(exit, now);
  const std::optional<std::string> late = lateNotice(at, seen);
  late_note_ = late.value_or("");
  std::vector<Action> actions = onBadExit(exit, late ? seen->at : at, now);
  late_note_.clear();
  return actions;
}

// A child that ended without a fault of its own: stopped by the launcher, or done.
std::vector<Action> Supervisor::onChildEnded(const ChildExit& exit, SteadyTime now) {
  if (phase_ == Phase::Stopping) {
    // The launcher's own stop ended it: a consequence of the cause already recorded.
    ended_.insert(exit.name);
    stopped_.push_back(exit.name);
    return {};
  }
  ended(exit.name, now);
  return {};
}

std::vector<Action> Supervisor::onBadExit(const ChildExit& exit, const RunPosition& at,
                                          SteadyTime now) {
  if (exit.name == kCoordinator) {
    // Under --on-sensor-failure stop (or with every sensor dead) the coordinator ends the run
    // because it was told of a death: its exit, whatever its status, belongs to that cause.
    if (stop_policy_cause_ && exit.signal == 0) {
      entries_[*stop_policy_cause_].fault.detail +=
          "; the coordinator then ended the run (" + exit.describe() + ")";
      ended(exit.name, now);
      return {};
    }
    return restartOrFail(exit, at);
  }
  // Once the coordinator has ended the run, nothing is restarted or re-planned any more.
  if (phase_ != Phase::Running) {
    return fail({RunFailureKind::ChildFailed, exit.name, exit.describe(), 0, at},
                exitFault(exit, at));
  }
  if (exit.name == config_.report_writer) return restartOrFail(exit, at);
  return onSensorAgentDeath(exit, at);
}

std::vector<Action> Supervisor::onSensorAgentDeath(const ChildExit& exit, const RunPosition& at) {
  const std::vector<int>* sensors = sensorsOf(exit.name);
  // Before the first episode a sensor agent that ends on its own is a launch that failed (a bad
  // program, a bad option): the run stops. One killed then is a death like any other, which the
  // failure policy answers (chaos seeds 15, 46, 54, 59).
  if (sensors == nullptr || sensors->empty() || (!at.episode && exit.signal == 0)) {
    return fail({RunFailureKind::ChildFailed, exit.name, exit.describe(), 0, at},
                exitFault(exit, at));
  }
  ended_.insert(exit.name);
  return onSensorsDead(exit.name, *sensors, exitFault(exit, at), exit.describe() + late_note_);
}

std::vector<Action> Supervisor::onExternalSensorsGone(const std::vector<int>& sensors,
                                                      const RunPosition& at) {
  if (phase_ != Phase::Running || !at.episode) return {};
  std::vector<int> fresh;
  for (const int j : sensors) {
    if (external_gone_.insert(j).second) fresh.push_back(j);
  }
  if (fresh.empty()) return {};
  const std::string how = "left the run (the SensorStatus writer of its participant went away)";
  return onSensorsDead("the external participant", fresh, Fault{FaultKind::SensorDied, kExternalProcess, fresh, at, how},
                       how);
}

std::vector<Action> Supervisor::onSensorsDead(const std::string& name,
                                              const std::vector<int>& sensors, Fault fault,
                                              const std::string& how) {
  Entry entry{std::move(fault), true, false};
  // The coordinator ends the run under policy stop, and under any policy when no sensor is left.
  const bool none_left =
      std::all_of(config_.sensor_agents.begin(), config_.sensor_agents.end(),
                  [this](const auto& agent) { return ended_.contains(agent.first); }) &&
      std::all_of(config_.external_sensors.begin(), config_.external_sensors.end(),
                  [this](int j) { return external_gone_.contains(j); });
  const bool stops = config_.on_sensor_failure == emulator::FailurePolicy::Stop || none_left;
  entry.fault.survived = !stops;
  entries_.push_back(std::move(entry));
  std::vector<Action> actions = {
      LogLine{false, name + " (sensor" + (sensors.size() == 1 ? " " : "s ") + listed(sensors) +
                         ") " + how + "; the coordinator applies the failure policy " +
                         std::string(wordOf(config_.on_sensor_failure))},
      NotifySensorsFailed{entries_.back().fault.process, sensors, how}};
  if (stops && !stop_policy_cause_) {
    // The coordinator ends the run; the launcher waits for it instead of stopping everything,
    // so that the fusion center closes the run as after any end.
    stop_policy_cause_ = entries_.size() - 1;
    failure_ = RunFailure{RunFailureKind::ChildFailed, name,
                          how + "; the coordinator ends the run", 0, entries_.back().fault.at};
  }
  return actions;
}

// Only a killed process is restarted: one that exited on its own decided to end the run.
std::vector<Action> Supervisor::restartOrFail(const ChildExit& exit, const RunPosition& at) {
  int& restarts = exit.name == kCoordinator ? restarts_coordinator_ : restarts_fusion_center_;
  if (exit.signal == 0 || restarts >= config_.max_restarts) {
    return fail({RunFailureKind::ChildFailed, exit.name, exit.describe(), 0, at},
                exitFault(exit, at));
  }
  Entry entry{exitFault(exit, at), false, true};
  entry.fault.survived = true;
  entries_.push_back(std::move(entry));
  return {RestartChild{exit.name, ++restarts}};
}

std::vector<Action> Supervisor::onRestarted(const std::string& name, pid_t pid,
                                            const std::string& log_name) {
  for (auto it = entries_.rbegin(); it != entries_.rend(); ++it) {
    if (it->fault.process != name || !it->awaiting_restart) continue;
    it->awaiting_restart = false;
    const int attempt = name == kCoordinator ? restarts_coordinator_ : restarts_fusion_center_;
    const std::string how = "restarted with --resume (restart " + std::to_string(attempt) + " of " +
                            std::to_string(config_.max_restarts) + ", pid " + std::to_string(pid) +
                            ", log " + log_name + ")";
    it->fault.detail += "; " + how;
    return {LogLine{false, name + " " + it->fault.detail}};
  }
  return {};
}

std::vector<Action> Supervisor::onRestartFailed(const std::string& name, const std::string& what) {
  for (auto it = entries_.rbegin(); it != entries_.rend(); ++it) {
    if (it->fault.process != name || !it->awaiting_restart) continue;
    it->awaiting_restart = false;
    it->fault.survived = false;
    it->fault.detail += "; it could not be restarted: " + what;
    std::vector<Action> actions = {LogLine{true, "cannot restart " + name + ": " + what}};
    for (Action& a : fail({RunFailureKind::ChildFailed, name, it->fault.detail, 0, it->fault.at},
                          std::nullopt)) {
      actions.push_back(std::move(a));
    }
    return actions;
  }
  return {};
}

void Supervisor::onReply(const std::string& process, const FailureReply& reply) {
  for (Entry& entry : entries_) {
    if (entry.fault.process != process || !entry.awaiting_reply) continue;
    entry.awaiting_reply = false;
    entry.fault.detail += "; " + reply.reason;
    if (reply.schedule_version != 0) entry.fault.schedule_version = reply.schedule_version;
    return;
  }
}

std::vector<Action> Supervisor::onSignal(int signal, const RunPosition& at) {
  if (phase_ == Phase::Stopping || phase_ == Phase::Done) return {};
  const std::string reason = "interrupted by " + signalName(signal);
  return fail({RunFailureKind::Interrupted, "", reason, signal, at},
              Fault{FaultKind::Interrupted, kLauncherProcess, {}, at, reason});
}

std::vector<Action> Supervisor::onTick(SteadyTime now, const RunPosition& at) {
  if (phase_ == Phase::Stopping || phase_ == Phase::Done) return {};
  if (deadline_ && now >= *deadline_) {
    const std::string limit =
        "the run did not end within --timeout " + seconds(*config_.timeout) + " s";
    return fail({RunFailureKind::TimedOut, "", "the run did not end within --timeout", 0, at},
                Fault{FaultKind::Timeout, kLauncherProcess, {}, at, limit});
  }
  if (phase_ == Phase::AwaitFusionCenter && now >= phase_until_) {
    const std::string reason = "did not exit within " + seconds(config_.fusion_center_exit_limit) +
                               " s after the coordinator ended the run";
    return fail({RunFailureKind::ChildFailed, config_.report_writer, reason, 0, at},
                Fault{FaultKind::ProcessHung, config_.report_writer, {}, at, reason});
  }
  // Sensor agents still running after their limit are stopped by the executable; that alone
  // does not fail a run whose report is written.
  if (phase_ == Phase::AwaitSensorAgents && now >= phase_until_) phase_ = Phase::Done;
  return {};
}

void Supervisor::onStopped() { phase_ = Phase::Done; }

// The first failure is the run's; the later ones (a second death, a signal while stopping) are
// not: they follow from the stop.
std::vector<Action> Supervisor::fail(RunFailure failure, std::optional<Fault> fault) {
  if (fault) entries_.push_back({std::move(*fault), false, false});
  if (!failure_) failure_ = std::move(failure);
  phase_ = Phase::Stopping;
  return {StopRun{}};
}

// The run ends in order: the coordinator, then the fusion center (which writes the report),
// then the sensor agents.
void Supervisor::ended(const std::string& name, SteadyTime now) {
  ended_.insert(name);
  if (phase_ == Phase::Running && name == kCoordinator) {
    phase_ = Phase::AwaitFusionCenter;
    phase_until_ = now + config_.fusion_center_exit_limit;
  }
  if (phase_ == Phase::AwaitFusionCenter &&
      (config_.report_writer.empty() || ended_.contains(config_.report_writer))) {
    phase_ = Phase::AwaitSensorAgents;
    phase_until_ = now + config_.sensor_agent_exit_limit;
  }
  if (phase_ == Phase::AwaitSensorAgents &&
      std::all_of(config_.sensor_agents.begin(), config_.sensor_agents.end(),
                  [this](const auto& agent) { return ended_.contains(agent.first); })) {
    phase_ = Phase::Done;
  }
}

Fault Supervisor::exitFault(const ChildExit& exit, const RunPosition& at) const {
  const std::vector<int>* sensors = sensorsOf(exit.name);
  Fault fault{exit.signal != 0 ? FaultKind::ProcessKilled : FaultKind::ProcessFailed, exit.name,
              sensors != nullptr ? *sensors : std::vector<int>{}, at,
              exit.describe() + late_note_};
  if (scripted(exit)) {
    fault.kind = FaultKind::Crash;
    fault.detail = "scripted crash (the scenario's faults:), " + fault.detail;
  }
  return fault;
}

const std::vector<int>* Supervisor::sensorsOf(const std::string& name) const {
  for (const auto& [agent, sensors] : config_.sensor_agents) {
    if (agent == name) return &sensors;
  }
  return nullptr;
}

bool Supervisor::scripted(const ChildExit& exit) const {
  const std::vector<int>* sensors = sensorsOf(exit.name);
  if (exit.signal != SIGKILL || sensors == nullptr) return false;
  return std::any_of(
      config_.scripted_crash_sensors.begin(), config_.scripted_crash_sensors.end(),
      [&](int j) { return std::find(sensors->begin(), sensors->end(), j) != sensors->end(); });
}

std::vector<Fault> Supervisor::faults() const {
  std::vector<Fault> out;
  for (const Entry& entry : entries_) {
    out.push_back(entry.fault);
    if (entry.awaiting_reply)
      out.back().detail += "; the coordinator did not answer the failure notice";
  }
  return out;
}

}  // namespace sensornet::launcher
