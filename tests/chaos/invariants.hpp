#pragma once
// What must hold after a chaos trial, whatever was injected, recomputed from what the run left
// behind (its report, its episode log, the launcher's exit code, the processes still running)
// and from a clean run with the same seed; never taken from the report's own verdict.
//
//   TrialRecord record{trial, injected, exit_code, report, log_text, clean_costs, leftovers};
//   for (const std::string& v : checkInvariants(record)) std::cout << v << '\n';
//
// Each violation is one short sentence naming the invariant, the episode or sensor and the
// numbers, e.g. "accounting: episode 3 sensor 2: sent 14 != received 12 + lost 1 + dropped 0".

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fault_schedule.hpp"

namespace sensornet::chaos {

// `object[key]`, or null where `object` is not an object or has no `key`. The checker reads
// whatever a faulted run left, and nlohmann's const operator[] reads past the end on a missing
// key (undefined behaviour: the checker itself segfaulted on such a report).
[[nodiscard]] const nlohmann::json& field(const nlohmann::json& object, std::string_view key);

// A planned fault as it was carried out.
struct InjectedFault {
  PlannedFault planned;
  bool injected = false;
  std::string note;               // why not, or which process it hit ("pid 123")
  int agent = -1;                 // SensorAgent: the agent it hit (another when that one was dead)
  double at_s = 0.0;              // wall seconds after the launch
  std::size_t logged_before = 0;  // episodes in the episode log at that moment
  double healed_at_s = -1.0;      // network faults: when it was healed (-1: not)
};

struct TrialRecord {
  Trial trial;
  std::vector<InjectedFault> faults;
  int exit_code = -1;     // the launcher's, 128 + signal when killed
  bool ended = true;      // the launcher ended within the trial's time limit
  std::optional<nlohmann::json> report;  // report.json, when there is one that parses
  bool report_exists = false;
  std::string episode_log;  // report.jsonl, as bytes
  // The clean run's realized cost of each episode, null where it was not complete.
  std::vector<std::optional<double>> clean_costs;
  std::vector<std::string> leftovers;  // command lines of the run's processes still alive
  std::string skipped;  // why the trial could not run here (a network trial without root)
  double ended_at_s = 0.0;  // when the launcher ended (or the trial gave up on it)
  double report_written_at_s = -1.0;  // when report.json was last written (-1: no report)
};

// The outcome the table of docs/ARCHITECTURE.md ("Run outcome") gives for what was injected.
struct ExpectedOutcome {
  std::vector<int> exit_codes;
  std::vector<std::string> statuses;  // empty: not checked (the launcher was killed)
  std::string why;
};

[[nodiscard]] ExpectedOutcome expectedOutcome(const TrialRecord& r);
[[nodiscard]] std::vector<std::string> checkInvariants(const TrialRecord& r);

}  // namespace sensornet::chaos
