#pragma once
// Watching the processes of a launched run until they are done or the run must stop: shows
// progress while it waits, and turns what happens (a child failing, Ctrl-C, the time limit)
// into the one reason the run ended, and remembers every child that ended badly on its own
// (with where the run was then) for the report's faults.
//
//   RunSupervisor supervisor(group, progress, deadline);
//   if (supervisor.awaitExit("coordinator", RunSupervisor::kNoLimit) && ...) { ... }
//   if (const auto& failure = supervisor.failure()) report(*failure);
//   for (const ChildFault& f : supervisor.childFaults()) ...;   // "sensor_agent-3 killed by ..."

#include <chrono>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "process_group.hpp"
#include "progress_watcher.hpp"

namespace sensornet::launcher {

enum class RunFailureKind { ChildFailed, Interrupted, TimedOut };

struct RunFailure {
  RunFailureKind kind = RunFailureKind::ChildFailed;
  std::string child;   // the child that failed (ChildFailed)
  std::string reason;  // one line: "exited with status 1", "interrupted by SIGINT", ...
  int signal = 0;      // the interrupting signal (Interrupted)
  RunPosition at;      // where the run was when it happened
};

// A child that ended badly (non-zero status, killed) before the launcher stopped anything.
struct ChildFault {
  ChildExit exit;
  RunPosition at;  // where the run was when the launcher saw it end
  bool survived = false;  // the response to it let the run go on (see ChildEndResponse)
};

// What the caller makes of a child that ended badly: return true when the run goes on (the
// child was restarted under the same name, or its loss is survivable), false when the run fails.
using ChildEndResponse = std::function<bool(const ChildExit&, const RunPosition&)>;

class RunSupervisor {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::chrono::milliseconds kNoLimit = std::chrono::hours(24 * 365);

  // `deadline`: when the whole run must be over (--timeout), if ever.
  RunSupervisor(ProcessGroup& group, ProgressWatcher& progress,
                std::optional<Clock::time_point> deadline);

  // Without a response every child that ends badly fails the run.
  void respondWith(ChildEndResponse response) { response_ = std::move(response); }
  // Called once per watch step (every 50 ms or so), e.g. to read answers to commands.
  void onEveryStep(std::function<void()> hook) { every_step_ = std::move(hook); }

  // Watches until `name` has ended successfully (true), or until the run fails or `limit`
  // passes (false; failure() tells which, and stays empty when only `limit` passed).
  [[nodiscard]] bool awaitExit(const std::string& name, std::chrono::milliseconds limit);
  // Records a failure found by the caller (the first one recorded wins); fills in `at`.
  void fail(RunFailure failure);
  [[nodiscard]] const std::optional<RunFailure>& failure() const noexcept { return failure_; }
  [[nodiscard]] const std::vector<ChildFault>& childFaults() const noexcept {
    return child_faults_;
  }

 private:
  // Shows the progress reported meanwhile and collects the children that ended.
  void step();

  ProcessGroup& group_;
  ProgressWatcher& progress_;
  std::optional<Clock::time_point> deadline_;
  std::set<std::string> ended_;
  std::optional<RunFailure> failure_;
  std::vector<ChildFault> child_faults_;
  ChildEndResponse response_;
  std::function<void()> every_step_;
};

}  // namespace sensornet::launcher
