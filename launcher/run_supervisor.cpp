#include "run_supervisor.hpp"

#include <csignal>

#include "interrupts.hpp"
#include "sensornet/emulator/messages.hpp"

namespace sensornet::launcher {
namespace {

constexpr std::chrono::milliseconds kWatchStep{50};

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

}  // namespace

RunSupervisor::RunSupervisor(ProcessGroup& group, ProgressWatcher& progress,
                             std::optional<Clock::time_point> deadline)
    : group_(group), progress_(progress), deadline_(deadline) {}

bool RunSupervisor::awaitExit(const std::string& name, std::chrono::milliseconds limit) {
  const auto until = Clock::now() + limit;
  for (;;) {
    if (failure_) return false;
    if (ended_.contains(name)) return true;
    if (Clock::now() >= until) return false;
    step();
  }
}

void RunSupervisor::fail(RunFailure failure) {
  if (failure_) return;
  failure.at = progress_.positionAt(emulator::wallNowNs());
  failure_ = std::move(failure);
}

void RunSupervisor::step() {
  progress_.poll(kWatchStep);
  if (every_step_) every_step_();
  for (const ChildExit& exit : group_.reap()) {
    if (exit.succeeded()) {
      ended_.insert(exit.name);
      continue;
    }
    const RunPosition at = progress_.positionAt(emulator::wallNowNs());
    const bool survived = !failure_ && response_ && response_(exit, at);
    child_faults_.push_back({exit, at, survived});
    // A restarted child runs again under its name: the run still waits for it to end.
    if (!group_.isRunning(exit.name)) ended_.insert(exit.name);
    if (!survived) fail({RunFailureKind::ChildFailed, exit.name, exit.describe(), 0, {}});
  }
  if (const int signal = pendingInterrupt()) {
    fail({RunFailureKind::Interrupted, "", "interrupted by " + signalName(signal), signal, {}});
  }
  if (deadline_ && Clock::now() >= *deadline_) {
    fail({RunFailureKind::TimedOut, "", "the run did not end within --timeout", 0, {}});
  }
}

}  // namespace sensornet::launcher
