#pragma once
// The wiring of the supervisor core (sensornet/launcher/supervisor.hpp) to the real run: every
// watch step (50 ms) it shows the progress reported meanwhile, feeds the core the children that
// ended, the coordinator's replies to failure notices, an interrupting signal and the clock, and
// carries out what the core decides (restart with --resume, send a failure notice, stop
// everything, log a line). Nothing is decided here.
//
//   Supervisor core(config, Clock::now());
//   superviseRun(core, {group, progress, notices, plan.children, plan.log_dir});
//   if (const auto& failure = core.failure()) explain(*failure);
//   settle(core.faults(), core.interrupted());

#include <filesystem>
#include <string>
#include <vector>

#include "sensornet/launcher/failure_notices.hpp"
#include "sensornet/launcher/process_group.hpp"
#include "sensornet/launcher/progress_watcher.hpp"
#include "sensornet/launcher/supervisor.hpp"

namespace sensornet::launcher {

// What the wiring drives: the children as started (a restart runs the same command with
// --resume), their log folder, and the launcher's DDS entities.
struct RunHandles {
  ProcessGroup& group;
  ProgressWatcher& progress;
  FailureNotices& notices;
  const std::vector<ChildSpec>& children;
  std::filesystem::path log_dir;
  std::vector<int> external_sensors;  // watched for a participant that leaves mid-run
};

// Watches the run until the core says it is over.
void superviseRun(Supervisor& core, RunHandles run);

}  // namespace sensornet::launcher
