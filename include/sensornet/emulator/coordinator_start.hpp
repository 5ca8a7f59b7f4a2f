#pragma once
// How `coordinator serve` starts a run: the request checked before any planning, then either a
// fresh journal (schedule version 1: a schedule file's, or planned with the run's surrogate) or
// the journal it resumes from, checked to be this run's.
//
//   checkServeRequest(config, run.scenario, "scenario.yaml", surrogate);   // or InputError
//   CoordinatorJournal journal = resume ? resumedJournal(config, run, "state.json", "scenario.yaml")
//                                       : freshJournal(config, run, surrogate, schedule_file);

#include <cstdint>
#include <optional>
#include <string>

#include "sensornet/planning/planner.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/coordinator_core.hpp"
#include "sensornet/emulator/coordinator_journal.hpp"
#include "sensornet/emulator/run_input_state.hpp"  // RunScenario
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

// Refuses, naming the option, what cannot start: --network-aware without the scenario's
// network: section (`scenario_path` is named), a closed loop (config.replan_every_s) with a
// surrogate other than info or cov.
void checkServeRequest(const CoordinatorConfig& config, const Scenario& scenario,
                       const std::string& scenario_path, PlanSurrogate surrogate);

// The journal of a run that starts afresh: its header from `config` and the run, the re-planner's
// settings, and version 1 (firstVersion).
[[nodiscard]] CoordinatorJournal freshJournal(const CoordinatorConfig& config,
                                              const RunScenario& run, PlanSurrogate surrogate,
                                              const std::optional<RateSchedule>& schedule_file);

// The journal at `state_path`, checked to be this run's (checkJournalOfRun); `config` takes the
// run's own episode count and time scale from it, whatever the command line said. A journal
// of another run id is used with a warning (a run restarted under a new id).
[[nodiscard]] CoordinatorJournal resumedJournal(CoordinatorConfig& config, const RunScenario& run,
                                                const std::string& state_path,
                                                const std::string& scenario_path);

}  // namespace sensornet::emulator
