#pragma once
// The cells of `sensornet sweep` (experiment_file.hpp) measured in process, and their results
// file: one JSON line per cell, appended as each cell ends, so that a sweep stopped at any point
// (Ctrl-C, a crash, a full disk) keeps every cell it finished and a re-run skips them.
//
//   SweepResults results("sweeps/fig1/results.jsonl");     // reads what an earlier run finished
//   for (const SweepCell& cell : experiment.cells) {
//     if (results.has(cell.key())) continue;
//     results.append(runSweepCell(cell, threads, stop));      // {"key", axes..., "status", ...}
//   }
//   results.writeCsv("sweeps/fig1/results.csv");
//
// A cell is measured as `coordinator plan` and `fusion_center evaluate` measure it: the same
// plan for the same scenario and planner, the same Monte Carlo for the same seed and runs (the
// closed loop: `fusion_center evaluate --replan-every`). An emulated cell (emulate:) is planned
// the same way and measured by the EmulatedRunner the caller gives: the launcher's whole run.

#include <atomic>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/io/experiment_file.hpp"

namespace sensornet::evaluation {

// Thrown by runSweepCell when `stop` was set while it ran (the cell is not a result).
struct SweepStopped : std::runtime_error {
  SweepStopped() : std::runtime_error("stopped") {}
};

// Measures a cell of `emulate:` (cell.emulate) by a whole emulated run of its scenario and
// `schedule`: the launcher's, which starts `sensornet launch`. It fills `row` with what the run
// gave (mean, ci95, std, arrivals_mean, run_status, exit_code, counts, report) and throws
// std::runtime_error with the reason when the run gave no measurement (the row keeps what it
// filled), SweepStopped when `stop` was set while it ran.
using EmulatedRunner = std::function<void(const SweepCell& cell, const RateSchedule& schedule,
                                          const std::atomic<bool>& stop, nlohmann::json& row)>;

// One row: the cell's key and axes, then "status" ("ok", or "failed" with "reason"), the plan
// (plan_status, plan_seconds, objective, bracket_info, bracket_cov), the Monte Carlo (mean,
// ci95, std, runs, arrivals_mean; closed loop also open_mean, gain_mean, gain_ci95) or the
// emulated run (`emulate`), seconds. A cell whose scenario, plan or measurement throws is a
// failed row, not an exception; an emulated cell without `emulate` is one.
[[nodiscard]] nlohmann::json runSweepCell(const SweepCell& cell, int threads,
                                          const std::atomic<bool>& stop,
                                          const EmulatedRunner& emulate = {});

// The columns of results.csv, in order (a row lacks the ones its cell has not).
[[nodiscard]] const std::vector<std::string>& sweepColumns();

class SweepResults {
 public:
  // Reads `path` when it exists: every complete line is a finished cell; a torn last line (a
  // crash mid-write) is cut off. Throws InputError naming the path for a line that is not a
  // result row (another file's), or when it cannot be read or opened for appending.
  explicit SweepResults(std::string path);

  [[nodiscard]] bool has(const std::string& key) const { return rows_.count(key) != 0; }
  [[nodiscard]] std::size_t size() const { return rows_.size(); }
  [[nodiscard]] std::size_t failed() const;
  // Forgets the failed rows, so that their cells run again (--retry-failed); the file keeps
  // them until a newer row of the same key supersedes them.
  void forgetFailed();
  // Appends one row and flushes it to the disk; throws std::runtime_error with the system's
  // reason when it cannot.
  void append(const nlohmann::json& row);
  // The last row of every key, in the order of `keys` (cells not in the results left out).
  [[nodiscard]] std::vector<nlohmann::json> rows(const std::vector<std::string>& keys) const;
  // rows(keys) as CSV with sweepColumns(); written atomically.
  void writeCsv(const std::string& path, const std::vector<std::string>& keys) const;

 private:
  std::string path_;
  std::map<std::string, nlohmann::json> rows_;
};

}  // namespace sensornet::evaluation
