#pragma once
// The runs live on this host, for `sensornet watch` and `sensornet status` without --run-id: the
// current-run record (run_files.hpp) and every run in the scratch folder whose launcher holds
// its <scratch>/<run id>/launch.lock (run_lock.hpp; the kernel lists held locks in /proc/locks,
// so looking takes no lock and never gets in a launch's way). The choice itself is
// sensornet/launcher/run_choice.hpp.
//
//   options.run.run_id = chooseLiveRun(options.run.run_id, options.run.domain_id).run_id;

#include <optional>
#include <string>
#include <vector>

#include "sensornet/launcher/run_choice.hpp"

namespace sensornet::launcher {

// The runs in the scratch folder whose launcher holds the lock, by run id.
[[nodiscard]] std::vector<LiveRun> liveRunsInScratch();

// The run given (with its launcher's pid when this host knows it), else the one live run; throws
// InputError naming --run-id when no run or several are live (listing them). Fills `domain_id`
// from the record when the user gave none.
[[nodiscard]] LiveRun chooseLiveRun(const std::string& given, std::optional<int>& domain_id);

// The --security folder the run's launcher was started with, if this host runs it.
[[nodiscard]] std::optional<std::string> securityOfLauncher(pid_t launcher_pid);

}  // namespace sensornet::launcher
