#include "sensornet/emulator/coordinator_start.hpp"

#include <spdlog/spdlog.h>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/core/plan_status.hpp"
#include "sensornet/emulator/replanner.hpp"

namespace sensornet::emulator {

ScheduleVersion firstVersion(const Scenario& scenario, PlanSurrogate surrogate, bool network_aware,
                             const std::optional<RateSchedule>& schedule_file) {
  ScheduleVersion initial;
  initial.version = 1;
  if (schedule_file) {
    initial.schedule = *schedule_file;
    initial.surrogate = SurrogateKind::File;
  } else {
    PlanRequest request;
    request.surrogate = surrogate;
    if (network_aware) request.delivery = deliveryFactors(scenario);
    const PlanResult plan = planSchedule(scenario, request);
    spdlog::info("initial {}{} schedule: {} after {} iterations in {:.3f} s", wordOf(surrogate),
                 network_aware ? " network-aware" : "", statusText(plan.status, plan.failure),
                 plan.iterations, plan.solve_seconds);
    initial.schedule = plan.schedule;
    initial.surrogate = surrogateKindOf(surrogate);
  }
  initial.bracket = computeBracket(scenario, initial.schedule);
  spdlog::info("bracket of schedule v1: [{:.6g}, {:.6g}]", initial.bracket.info,
               initial.bracket.cov);
  return initial;
}

void checkJournalOfRun(const CoordinatorJournal& journal, const std::string& journal_path,
                       const std::string& digest, const std::string& scenario_path,
                       std::uint64_t seed) {
  const auto mismatch = [&](const char* field, const std::string& journal_value,
                            const std::string& ours) {
    throw InputError(journal_path, field,
                     "the journal's " + journal_value + ", got " + ours +
                         " (resume with the run's own --scenario and --seed)");
  };
  if (journal.scenario_digest != digest) {
    mismatch("scenario_digest", journal.scenario_digest,
             digest + " from --scenario " + scenario_path);
  }
  if (journal.seed != seed) {
    mismatch("seed", std::to_string(journal.seed), "--seed " + std::to_string(seed));
  }
}

void checkServeRequest(const CoordinatorConfig& config, const Scenario& scenario,
                       const std::string& scenario_path, PlanSurrogate surrogate) {
  if (config.network_aware && !scenario.network) {
    throw InputError(scenario_path, "network",
                     "a network: section (--network-aware plans for the rates it delivers)");
  }
  if (config.replan_every_s && surrogate != PlanSurrogate::Information &&
      surrogate != PlanSurrogate::Covariance) {
    throw InputError("--replan-every", "--surrogate",
                     "info or cov (the closed loop re-plans with the run's surrogate, within "
                     "the switch margin), got " + std::string(describe(surrogate)));
  }
}

CoordinatorJournal freshJournal(const CoordinatorConfig& config, const RunScenario& run,
                                PlanSurrogate surrogate,
                                const std::optional<RateSchedule>& schedule_file) {
  CoordinatorJournal journal = journalHeader(config, run.digest, run.seed);
  journal.settings = initialSettings(run.scenario, surrogate);
  journal.versions.push_back(
      firstVersion(run.scenario, surrogate, config.network_aware, schedule_file));
  return journal;
}

CoordinatorJournal resumedJournal(CoordinatorConfig& config, const RunScenario& run,
                                  const std::string& state_path,
                                  const std::string& scenario_path) {
  CoordinatorJournal journal = loadJournal(state_path, run.scenario);
  checkJournalOfRun(journal, state_path, run.digest, scenario_path, run.seed);
  if (journal.run_id != config.run_id) {
    spdlog::warn("resuming run {} from the journal of run {}", config.run_id, journal.run_id);
  }
  config.episodes = static_cast<int>(journal.episodes_planned);
  config.time_scale = journal.time_scale;
  spdlog::info("resuming from {}: schedule v{}, {} episodes reported, {} failed sensor(s)",
               state_path, journal.versions.back().version, journal.episodes_reported.size(),
               journal.settings.failed.size());
  return journal;
}

}  // namespace sensornet::emulator
