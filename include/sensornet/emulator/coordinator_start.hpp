#pragma once
// How `coordinator serve` starts a run: schedule version 1 (a schedule file's, or planned with
// the run's surrogate), and the check that a journal it resumes from is this run's.
//
//   journal.versions.push_back(firstVersion(scenario, PlanSurrogate::Covariance, false, {}));
//   checkJournalOfRun(loaded, "state.json", digest, "scenario.yaml", seed);  // or InputError

#include <cstdint>
#include <optional>
#include <string>

#include "sensornet/planning/planner.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/coordinator_journal.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator {

// Version 1 from (episode 0, 0 s): `schedule_file` when given (SurrogateKind::File), else the
// plan of `surrogate` (with `network_aware`, for the rates the scenario's network delivers); its
// bracket over [0, T] from P0. Logs the plan and the bracket.
[[nodiscard]] ScheduleVersion firstVersion(const Scenario& scenario, PlanSurrogate surrogate,
                                           bool network_aware,
                                           const std::optional<RateSchedule>& schedule_file);

// Throws InputError naming `journal_path` when the journal is another run's: another scenario
// (digest; `scenario_path` is named in the message) or another seed.
void checkJournalOfRun(const CoordinatorJournal& journal, const std::string& journal_path,
                       const std::string& digest, const std::string& scenario_path,
                       std::uint64_t seed);

}  // namespace sensornet::emulator
