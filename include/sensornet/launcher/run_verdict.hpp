#pragma once
// The run's status and the launcher's exit code, decided in one place from what the launcher
// saw and what the fusion center's report says (docs/ARCHITECTURE.md, "Run outcome"):
//
//   | exit | status                 |
//   | 0    | completed              |
//   | 1    | failed / interrupted   |
//   | 2    | (bad input, no run)    |
//   | 3    | degraded               |
//   | 4    | a --require failed     |  (run_requirements.hpp: gatedExitCode)
//
// The rule is run_status.hpp's, the one every decider uses: the fusion center gathers what it
// saw into its report's status; the launcher has the final word on process faults: a signal
// makes the run interrupted, a fault the run did not survive makes it failed, a survived one
// makes a completed report degraded. No file is read here: the
// caller reads the report (run_outcome.hpp) and passes what it found.
//
//   ReportSeen seen{true, "", "completed", 20};
//   const Verdict v = decideVerdict(supervisor.faults(), supervisor.interrupted(), seen, 20);
//   exitCodeOf(v.status);   // 0

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/launcher/fault.hpp"

namespace sensornet::launcher {

// Exit codes of `sensornet launch` beyond command_line.hpp's 0, 1 and 2.
inline constexpr int kExitDegraded = 3;  // every episode ran, but a fault cost something

// completed 0, degraded 3, failed and interrupted 1.
[[nodiscard]] int exitCodeOf(emulator::RunStatus status);

// What the launcher found of the fusion center's report.
struct ReportSeen {
  bool readable = false;  // false: missing, not a report, or another run's (it was rebuilt)
  std::string problem;    // then what is wrong: "wrote no report at ..."
  std::string status;     // the report's `status`, as written
  std::uint64_t finished_episodes = 0;
  std::optional<std::uint64_t> complete_episodes;  // none: as many as finished
  std::uint64_t lost = 0;  // the report's summary: measurements sent and never received
};

struct Verdict {
  emulator::RunStatus status = emulator::RunStatus::Failed;
  std::vector<Fault> faults;  // the launcher's, and what settling the run added to them
};

[[nodiscard]] Verdict decideVerdict(std::vector<Fault> launcher_faults, bool interrupted,
                                    const ReportSeen& report, int episodes_planned);

}  // namespace sensornet::launcher
