#include "sensornet/launcher/run_choice.hpp"

#include <algorithm>

namespace sensornet::launcher {
namespace {

std::string described(const LiveRun& run) {
  std::string text = run.run_id + " (launcher pid " + std::to_string(run.launcher_pid);
  if (!run.started.empty()) text += ", started " + run.started;
  if (!run.log_dir.empty()) text += ", logs in " + run.log_dir;
  return text + ")";
}

}  // namespace

RunChoice chooseRun(const std::string& given, const std::optional<RecordedRun>& record,
                    const std::vector<LiveRun>& found, const std::string& record_path) {
  if (!given.empty()) {
    LiveRun run{given, 0, std::nullopt, "", ""};
    return {run, ""};
  }
  std::vector<LiveRun> live = found;
  if (record && record->launcher_alive) {
    const auto same = std::find_if(
        live.begin(), live.end(), [&](const LiveRun& r) { return r.run_id == record->run.run_id; });
    if (same == live.end()) {
      live.insert(live.begin(), record->run);
    } else if (!same->domain_id) {
      same->domain_id = record->run.domain_id;
    }
  }
  if (live.size() == 1) return {live.front(), ""};
  if (live.size() > 1) {
    std::string list;
    for (const LiveRun& r : live) list += (list.empty() ? "" : "; ") + described(r);
    return {std::nullopt, "one run id: " + std::to_string(live.size()) +
                              " runs are live on this host, which one? " + list};
  }
  if (record) {
    return {std::nullopt, "a run id: the last launched run, " + record->run.run_id +
                              ", is over (its launcher, pid " +
                              std::to_string(record->run.launcher_pid) + ", is gone)"};
  }
  return {std::nullopt, "a run id: no run launched by `sensornet launch` is going on here (no " +
                            record_path + ")"};
}

}  // namespace sensornet::launcher
