#pragma once
// Which run `sensornet watch` and `sensornet status` look at when no --run-id is given, decided
// from what this host knows, without reading it: the current-run record (the run launched last,
// and whether its launcher still lives) and the runs whose launcher holds its lock in the
// scratch folder. One live run is the answer; with several (two people sharing an account, two
// terminals) the user is asked to name one, and told which are live; with none, why not.
//
//   const RunChoice choice = chooseRun(given, record, found);
//   if (!choice.run) throw InputError("command line", "--run-id", choice.expected);

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace sensornet::launcher {

struct LiveRun {
  std::string run_id;
  pid_t launcher_pid = 0;
  std::optional<int> domain_id;  // when it was launched with --domain-id (the record says so)
  std::string log_dir;           // where its logs are ("" if not known)
  std::string started;           // "23:10:05" ("" if not known)
};

struct RecordedRun {
  LiveRun run;
  bool launcher_alive = true;
};

struct RunChoice {
  std::optional<LiveRun> run;
  // Otherwise what --run-id should have been, for the one-line error: "a run id: 2 runs are
  // live on this host (...)".
  std::string expected;
};

// `record_path` only names the record in the message when there is none.
[[nodiscard]] RunChoice chooseRun(const std::string& given,
                                  const std::optional<RecordedRun>& record,
                                  const std::vector<LiveRun>& found,
                                  const std::string& record_path);

}  // namespace sensornet::launcher
