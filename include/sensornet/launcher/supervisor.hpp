#pragma once
// What the launcher decides while a run goes on, free of processes, DDS and clocks: events in
// (a child's exit, a signal to the launcher, tick(now), a reply to a failure notice, a restart
// carried out), actions out (restart this process, tell the coordinator these sensors failed,
// stop everything, log this line). The `sensornet` executable feeds it what its process group,
// its DDS reader and its signal handler see, carries out its actions, and asks it at the end
// for the faults and the one reason the run failed. One cause, one fault: a child that exits
// because the launcher stopped the run, or because the coordinator ended it under
// --on-sensor-failure stop, is not a fault of its own.
//
//   Supervisor supervisor(config, now);
//   for (const Action& a : supervisor.onChildExit(exit, position, now)) carryOut(a);
//   for (const Action& a : supervisor.onTick(now, position)) carryOut(a);   // every watch step
//   supervisor.onReply("sensor_agent-3", reply);
//   if (supervisor.done()) { settle(supervisor.faults(), supervisor.interrupted()); }

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "sensornet/report/fault_causes.hpp"
#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/launcher/fault.hpp"

namespace sensornet::launcher {

using SteadyTime = std::chrono::steady_clock::time_point;

inline constexpr const char* kCoordinator = "coordinator";
inline constexpr const char* kFusionCenter = "fusion_center";
// Ours beside an external fusion center (--reference-fusion): same inputs, its own report.
inline constexpr const char* kReferenceFusionCenter = "reference_fusion_center";
inline constexpr const char* kLauncherProcess = "sensornet";
// The process of a fault of external sensors: a participant of the user's, not ours.
inline constexpr const char* kExternalProcess = "external";

// How a child ended.
struct ChildExit {
  std::string name;
  pid_t pid = 0;
  int exit_code = 0;  // when it exited
  int signal = 0;     // when a signal killed it (then exit_code is 128 + signal)
  [[nodiscard]] bool succeeded() const noexcept { return signal == 0 && exit_code == 0; }
  // "exited with status 3", "killed by signal 9 (Killed)".
  [[nodiscard]] std::string describe() const;
};

// The launcher's last look that found a child alive, before the look that found it dead: where
// the run was then (the later of that look and the child's last SensorStatus) and how many wall
// seconds passed until the child was found dead. Normally one watch step (50 ms); much more when
// the launcher itself was not running (SIGSTOP, starved of CPU) while the child died.
struct LastSeenAlive {
  RunPosition at;
  double unseen_s = 0.0;
};

// Longer than this unseen, a death is dated by the last sight of the child alive, not by the
// moment the launcher noticed it (StallWatch's slack: a loop that looks every 50 ms was stalled).
inline constexpr double kLateDeathNoticeS = 0.5;

// The one reason a run ended as failed or interrupted (for the lines on standard error).
enum class RunFailureKind { ChildFailed, Interrupted, TimedOut };
struct RunFailure {
  RunFailureKind kind = RunFailureKind::ChildFailed;
  std::string child;   // the child that failed (ChildFailed)
  std::string reason;  // one line: "exited with status 1", "interrupted by SIGINT", ...
  int signal = 0;      // the interrupting signal (Interrupted)
  RunPosition at;      // where the run was when it happened
};

// A reply of the coordinator to a failure notice.
struct FailureReply {
  bool accepted = false;
  std::uint32_t schedule_version = 0;  // the first version the policy published, 0 if none
  std::string reason;                  // "policy replan: version 3 from 1.25 s of episode 2; ..."
};

struct SupervisorConfig {
  // The sensor agents by name with the sensors each hosts; the coordinator and the fusion
  // center are kCoordinator and kFusionCenter.
  std::vector<std::pair<std::string, std::vector<int>>> sensor_agents;
  emulator::FailurePolicy on_sensor_failure = emulator::FailurePolicy::Replan;
  std::vector<int> scripted_crash_sensors;  // sensors of the scenario's `faults:` crashes
  std::vector<int> external_sensors;        // --external-sensors: a participant of the user's
  std::optional<std::chrono::milliseconds> timeout;  // --timeout, if any
  int max_restarts = 3;  // a coordinator or fusion center killed more often is not restarted
  // The child that writes the run's report (restarted with --resume when killed, awaited after
  // the coordinator ended the run): the fusion center; kReferenceFusionCenter or none ("") when
  // the fusion center is external.
  std::string report_writer = kFusionCenter;
  // After the coordinator ends the run the report writer writes its report and exits; the
  // sensor agents leave on the same RUN_SHUTDOWN.
  std::chrono::milliseconds fusion_center_exit_limit{15'000};
  std::chrono::milliseconds sensor_agent_exit_limit{5'000};
};

// Actions, carried out by the executable in the order given.
struct RestartChild {  // start `name` again with --resume; answer with onRestarted/-Failed
  std::string name;
  int attempt = 1;
};
struct NotifySensorsFailed {  // COMMAND_SENSORS_FAILED to the coordinator, resent until answered
  std::string process;
  std::vector<int> sensors;
  std::string detail;
};
// SIGTERM to every child but the fusion center, SIGKILL after a short grace; then the fusion
// center, with a longer one (on SIGTERM it closes its open episodes and writes the report).
// Report how each ended with onChildExit, then call onStopped.
struct StopRun {};
struct LogLine {
  bool error = false;  // an error (spdlog), else a line for the user ("sensornet: ...")
  std::string text;
};
using Action = std::variant<RestartChild, NotifySensorsFailed, StopRun, LogLine>;

class Supervisor {
 public:
  Supervisor(SupervisorConfig config, SteadyTime started);

  // `at`: where the run is now; `seen`: the last look that found the child alive, if known.
  [[nodiscard]] std::vector<Action> onChildExit(const ChildExit& exit, const RunPosition& at,
                                                SteadyTime now,
                                                std::optional<LastSeenAlive> seen = std::nullopt);
  // External sensors (--external-sensors) whose participant left the run mid-run: its
  // SensorStatus writer has been gone past the launcher's limit. A death like a sensor agent's,
  // which the failure policy answers; before the first episode or after the run ended, nothing.
  [[nodiscard]] std::vector<Action> onExternalSensorsGone(const std::vector<int>& sensors,
                                                          const RunPosition& at);
  // SIGINT, SIGTERM, SIGHUP to the launcher: the run is stopped and ends interrupted.
  [[nodiscard]] std::vector<Action> onSignal(int signal, const RunPosition& at);
  // Deadlines: --timeout, the fusion center's and the sensor agents' exit limits.
  [[nodiscard]] std::vector<Action> onTick(SteadyTime now, const RunPosition& at);
  void onReply(const std::string& process, const FailureReply& reply);
  [[nodiscard]] std::vector<Action> onRestarted(const std::string& name, pid_t pid,
                                                const std::string& log_name);
  [[nodiscard]] std::vector<Action> onRestartFailed(const std::string& name,
                                                    const std::string& what);
  // The StopRun was carried out: every child has ended.
  void onStopped();

  // Every child has ended, or has been stopped: the run is over.
  [[nodiscard]] bool done() const noexcept { return phase_ == Phase::Done; }
  [[nodiscard]] const std::optional<RunFailure>& failure() const noexcept { return failure_; }
  [[nodiscard]] bool interrupted() const noexcept {
    return failure_ && failure_->kind == RunFailureKind::Interrupted;
  }
  // The children that ended while the run was being stopped (none of them a fault).
  [[nodiscard]] const std::vector<std::string>& stoppedChildren() const noexcept {
    return stopped_;
  }
  // The faults in the order they happened; a notice still unanswered says so.
  [[nodiscard]] std::vector<Fault> faults() const;

 private:
  enum class Phase { Running, AwaitFusionCenter, AwaitSensorAgents, Stopping, Done };
  struct Entry {
    Fault fault;
    bool awaiting_reply = false;    // a failure notice went out for it
    bool awaiting_restart = false;  // a restart was asked for it
  };

  [[nodiscard]] std::vector<Action> onChildEnded(const ChildExit& exit, SteadyTime now);
  [[nodiscard]] std::vector<Action> onBadExit(const ChildExit& exit, const RunPosition& at,
                                              SteadyTime now);
  [[nodiscard]] std::vector<Action> onSensorAgentDeath(const ChildExit& exit,
                                                       const RunPosition& at);
  // The death of the process `name` that spoke for `sensors`, recorded as `fault`: the policy.
  [[nodiscard]] std::vector<Action> onSensorsDead(const std::string& name,
                                                  const std::vector<int>& sensors, Fault fault,
                                                  const std::string& how);
  [[nodiscard]] std::vector<Action> restartOrFail(const ChildExit& exit, const RunPosition& at);
  [[nodiscard]] std::vector<Action> fail(RunFailure failure, std::optional<Fault> fault);
  void ended(const std::string& name, SteadyTime now);
  [[nodiscard]] Fault exitFault(const ChildExit& exit, const RunPosition& at) const;
  [[nodiscard]] const std::vector<int>* sensorsOf(const std::string& name) const;
  [[nodiscard]] bool scripted(const ChildExit& exit) const;

  SupervisorConfig config_;
  std::optional<SteadyTime> deadline_;
  Phase phase_ = Phase::Running;
  SteadyTime phase_until_{};  // the limit of the AwaitFusionCenter or AwaitSensorAgents phase
  std::set<std::string> ended_;
  std::set<int> external_gone_;  // external sensors already answered as dead
  std::vector<std::string> stopped_;
  std::vector<Entry> entries_;
  std::optional<RunFailure> failure_;
  std::optional<std::size_t> stop_policy_cause_;  // the death the coordinator ends the run for
  // While onChildExit runs: when the death was noticed late, what the launcher knows of its
  // moment ("; found dead 1.0 s after it was last seen alive ..."), else "".
  std::string late_note_;
  int restarts_coordinator_ = 0;
  int restarts_fusion_center_ = 0;
};

}  // namespace sensornet::launcher
