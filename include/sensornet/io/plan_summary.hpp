#pragma once
// What `coordinator plan` says of a plan: the record written into the schedule file beside the
// rates, the one JSON line of --json, and the text summary. The program plans and writes; these
// decide the words and numbers.
//
//   const PlanResult plan = planSchedule(scenario, request);
//   PlanSummary s{plan, request.surrogate, deliveredBracket(scenario, plan.schedule, plan.bracket),
//                 network_aware};
//   writeScheduleFile(path, plan.schedule, planRecord(s));
//   printJson(planJsonLine(s, path));                     // or:
//   std::fputs(planSummaryText(s, scenario, scenario_path, path).c_str(), stdout);

#include <nlohmann/json.hpp>
#include <string>

#include "sensornet/planning/planner.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"

namespace sensornet {

// The bracket of what the scenario's network delivers of `schedule` in episode 0 (outages of
// other episodes left out); `planned`, the schedule's own bracket, without a network.
[[nodiscard]] CostBracket deliveredBracket(const Scenario& scenario, const RateSchedule& schedule,
                                           const CostBracket& planned);

struct PlanSummary {
  const PlanResult& plan;
  PlanSurrogate surrogate = PlanSurrogate::Covariance;
  CostBracket delivered;  // deliveredBracket of the plan's schedule
  bool network_aware = false;
};

// The schedule file's fields beside the rates: surrogate, objective, bracket, delivered_bracket,
// network_aware, status (mc: objective_half_width and episodes too).
[[nodiscard]] nlohmann::json planRecord(const PlanSummary& s);

// --json: the record's fields with iterations, substeps, solve_seconds, kkt_residual (null when
// not finite) and `out`, the path written.
[[nodiscard]] nlohmann::json planJsonLine(const PlanSummary& s, const std::string& out);

// The lines of the text summary: scenario, surrogate, bracket, delivered (with a network),
// written (`written_to`: a path, or "to standard output").
[[nodiscard]] std::string planSummaryText(const PlanSummary& s, const Scenario& scenario,
                                          const std::string& scenario_path,
                                          const std::string& written_to);

}  // namespace sensornet
