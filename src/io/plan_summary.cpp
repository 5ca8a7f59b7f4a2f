#include "sensornet/io/plan_summary.hpp"

#include <cmath>

#include "sensornet/core/network.hpp"
#include "sensornet/core/plan_status.hpp"
#include "sensornet/io/append_format.hpp"

namespace sensornet {
namespace {

nlohmann::json toJson(const CostBracket& bracket) {
  return {{"info", bracket.info}, {"cov", bracket.cov}};
}

bool monteCarlo(const PlanSummary& s) { return s.surrogate == PlanSurrogate::MonteCarlo; }

}  // namespace

CostBracket deliveredBracket(const Scenario& scenario, const RateSchedule& schedule,
                             const CostBracket& planned) {
  if (!scenario.network) return planned;
  return computeBracket(scenario, deliveredSchedule(schedule, *scenario.network, 0));
}

nlohmann::json planRecord(const PlanSummary& s) {
  nlohmann::json record = {{"surrogate", std::string(wordOf(s.surrogate))},
                           {"objective", s.plan.objective},
                           {"bracket", toJson(s.plan.bracket)},
                           {"delivered_bracket", toJson(s.delivered)},
                           {"network_aware", s.network_aware},
                           {"status", statusText(s.plan.status, s.plan.failure)}};
  if (monteCarlo(s)) {
    record["objective_half_width"] = s.plan.objective_half_width;
    record["episodes"] = s.plan.episodes;
  }
  return record;
}

nlohmann::json planJsonLine(const PlanSummary& s, const std::string& out) {
  nlohmann::json doc = {{"surrogate", std::string(wordOf(s.surrogate))},
                        {"objective", s.plan.objective},
                        {"bracket", toJson(s.plan.bracket)},
                        {"delivered_bracket", toJson(s.delivered)},
                        {"network_aware", s.network_aware},
                        {"iterations", s.plan.iterations},
                        {"substeps", s.plan.substeps},
                        {"solve_seconds", s.plan.solve_seconds},
                        {"status", statusText(s.plan.status, s.plan.failure)},
                        {"out", out}};
  doc["kkt_residual"] = std::isfinite(s.plan.kkt_residual) ? nlohmann::json(s.plan.kkt_residual)
                                                           : nlohmann::json(nullptr);
  if (monteCarlo(s)) {
    doc["objective_half_width"] = s.plan.objective_half_width;
    doc["episodes"] = s.plan.episodes;
  }
  return doc;
}

std::string planSummaryText(const PlanSummary& s, const Scenario& scenario,
                            const std::string& scenario_path, const std::string& written_to) {
  const PlanResult& plan = s.plan;
  const std::string status = statusText(plan.status, plan.failure);
  std::string out;
  appendf(out, "scenario   %s (n = %d states, M = %d sensors, T = %g s, N = %d)\n",
          scenario_path.c_str(), scenario.stateDim(), scenario.sensorCount(), scenario.horizon_s,
          scenario.intervals);
  if (monteCarlo(s)) {
    appendf(out,
            "surrogate  mc: E[J] = %.9g +- %.3g (95%%, fresh episodes), status %s, %d "
            "iterations, %lld episodes in %.3f s\n",
            plan.objective, plan.objective_half_width, status.c_str(), plan.iterations,
            plan.episodes, plan.solve_seconds);
  } else {
    appendf(out,
            "surrogate  %s: objective %.9g, status %s, %d iterations in %.3f s, %d RK4 "
            "steps per interval\n",
            std::string(wordOf(s.surrogate)).c_str(), plan.objective, status.c_str(),
            plan.iterations, plan.solve_seconds, plan.substeps);
  }
  appendf(out, "bracket    J(P_info) = %.9g <= E[J] <= J(P_cov) = %.9g\n", plan.bracket.info,
          plan.bracket.cov);
  if (scenario.network) {
    appendf(out, "delivered  J(P_info) = %.9g <= E[J] <= J(P_cov) = %.9g (%s)\n", s.delivered.info,
            s.delivered.cov,
            s.network_aware ? "planned for the network" : "the network was not planned for");
  }
  appendf(out, "written    %s\n", written_to.c_str());
  return out;
}

}  // namespace sensornet
