#pragma once
// How a plan ended (PlanResult::status), as a word (core/words.hpp) with one spelling each, and
// the one rule of which endings are solved: a plan that is published, written or kept as it is
// without a warning.
//
//   const PlanResult plan = planSchedule(scenario, request);
//   if (!solved(plan.status)) warn(statusText(plan.status, plan.failure));  // "failed: ..."
//   json["status"] = statusText(plan.status, plan.failure);                  // "optimal"

#include <array>
#include <string>
#include <string_view>

#include "sensornet/core/words.hpp"

namespace sensornet {

enum class PlanStatus {
  Optimal,        // the KKT tolerance was met
  Acceptable,     // IPOPT's looser tolerance was met
  MaxIterations,  // the iteration limit ended the solve
  TimeLimit,      // the time limit ended the solve
  Stalled,        // no step decreases the cost any more
  Stopped,        // the progress callback returned false
  NotOptimized,   // Uniform, or nothing to plan
  Failed,         // the solver failed (PlanResult::failure says why); its best point is kept
  Improved,       // mc: the refined schedule passed the paired tests against its warm start
  KeptStart,      // mc: it did not (or nothing better was found): the warm start is returned
};

template <>
struct Words<PlanStatus> {
  using S = PlanStatus;
  static constexpr std::array<WordOf<S>, 10> kTable{{{S::Optimal, "optimal"},
                                                     {S::Acceptable, "acceptable"},
                                                     {S::MaxIterations, "max_iterations"},
                                                     {S::TimeLimit, "time_limit"},
                                                     {S::Stalled, "stalled"},
                                                     {S::Stopped, "stopped"},
                                                     {S::NotOptimized, "not_optimized"},
                                                     {S::Failed, "failed"},
                                                     {S::Improved, "improved"},
                                                     {S::KeptStart, "kept_start"}}};
};

// The plan is what its method promises: optimal or acceptable, nothing to optimize, or (mc)
// either answer of the paired tests. The rest (limits, stalls, stops, failures) are the best
// point found.
[[nodiscard]] constexpr bool solved(PlanStatus status) {
  return status == PlanStatus::Optimal || status == PlanStatus::Acceptable ||
         status == PlanStatus::NotOptimized || status == PlanStatus::Improved ||
         status == PlanStatus::KeptStart;
}

// The status as reports and logs write it: its word, and for Failed "failed: <failure>".
[[nodiscard]] inline std::string statusText(PlanStatus status, std::string_view failure) {
  std::string text(wordOf(status));
  if (status == PlanStatus::Failed && !failure.empty()) text += ": " + std::string(failure);
  return text;
}

}  // namespace sensornet
