#include "sensornet/emulator/coordinator_start.hpp"

#include <spdlog/spdlog.h>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/core/plan_status.hpp"

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

}  // namespace sensornet::emulator
