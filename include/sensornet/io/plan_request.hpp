#pragma once
// What `coordinator plan` asks the planner, from the user's choices: the request checked against
// the scenario (bad input named, before the solve), the solve's progress in the log, and the
// schedule file written to a path or to standard output.
//
//   PlanChoices choices;                       // surrogate, method, limits, exclusions, ...
//   choices.excluded = {3};
//   PlanRequest request = planRequest(scenario, "s.yaml", choices);   // or InputError
//   request.progress = planProgressLog(choices.surrogate);           // a line every 2 s
//   const PlanResult plan = planSchedule(scenario, request);
//   writePlannedSchedule("-", plan.schedule, planRecord(summary));    // - : standard output

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/planning/planner.hpp"

namespace sensornet {

struct PlanChoices {
  PlanSurrogate surrogate = PlanSurrogate::Covariance;
  PlanMethod method = PlanMethod::ProjectedGradient;
  double tolerance = PlanRequest{}.tolerance;
  int max_iterations = 500;
  double max_seconds = 120.0;
  bool max_seconds_given = false;  // else the Monte Carlo planner gets kMonteCarloPlanSeconds
  std::vector<int> excluded;       // sensors out of service (0-based)
  bool network_aware = false;      // plan for the rates the scenario's network delivers
  std::string warm_start_path;     // a schedule file to start from (empty: uniform)
};

// The Monte Carlo planner's wall-time limit when none is given (a minute's budget with room for
// the final evaluation).
inline constexpr double kMonteCarloPlanSeconds = 55.0;

// The request for `choices` on `scenario` (loaded from `scenario_path`, named in errors). Throws
// InputError for an excluded sensor the scenario does not have, --network-aware without a
// network: section, or a warm start that is not a schedule of the scenario.
[[nodiscard]] PlanRequest planRequest(const Scenario& scenario, const std::string& scenario_path,
                                      const PlanChoices& choices);

// A progress callback that logs the iteration and objective every 2 s of wall time.
[[nodiscard]] std::function<bool(const PlanProgress&)> planProgressLog(PlanSurrogate surrogate);

// The schedule file (the schedule with `record`'s keys) at `out_path`, atomically, or on
// standard output for "-". Throws when it cannot be written.
void writePlannedSchedule(const std::string& out_path, const RateSchedule& schedule,
                          const nlohmann::json& record);

}  // namespace sensornet
