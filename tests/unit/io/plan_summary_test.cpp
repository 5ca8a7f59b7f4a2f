// What `coordinator plan` says of a plan: the schedule file's record, the --json line and the
// text summary, from a plan made up here (no solve): the words, the mc fields, a failed
// solve's reason, a NaN residual as null, the delivered line only with a network.
#include "sensornet/io/plan_summary.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "sensornet/io/scenario_file.hpp"

namespace sensornet {
namespace {

Scenario defaultScenario() {
  return loadScenarioFile(std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml");
}

PlanResult madeUpPlan() {
  PlanResult plan;
  plan.objective = 1.5;
  plan.bracket = {1.25, 2.5};
  plan.iterations = 7;
  plan.substeps = 4;
  plan.solve_seconds = 0.25;
  plan.status = PlanStatus::Failed;
  plan.failure = "locally infeasible";
  plan.kkt_residual = std::numeric_limits<double>::quiet_NaN();
  return plan;
}

TEST(PlanSummary, TheRecordSaysTheSurrogateStatusAndBrackets) {
  const PlanResult plan = madeUpPlan();
  const PlanSummary s{plan, PlanSurrogate::Information, {1.0, 3.0}, true};
  const nlohmann::json r = planRecord(s);
  EXPECT_EQ(r.at("surrogate"), "info");
  EXPECT_EQ(r.at("status"), "failed: locally infeasible");
  EXPECT_EQ(r.at("bracket").at("cov"), 2.5);
  EXPECT_EQ(r.at("delivered_bracket").at("info"), 1.0);
  EXPECT_EQ(r.at("network_aware"), true);
  EXPECT_FALSE(r.contains("episodes"));    // mc only
  EXPECT_FALSE(r.contains("iterations"));  // --json only
}

TEST(PlanSummary, TheJsonLineAddsTheSolveAndNullForANanResidual) {
  PlanResult plan = madeUpPlan();
  plan.status = PlanStatus::Improved;
  plan.episodes = 1234;
  plan.objective_half_width = 0.125;
  const PlanSummary s{plan, PlanSurrogate::MonteCarlo, plan.bracket, false};
  const nlohmann::json j = planJsonLine(s, "plan.json");
  EXPECT_EQ(j.at("surrogate"), "mc");
  EXPECT_EQ(j.at("status"), "improved");
  EXPECT_TRUE(j.at("kkt_residual").is_null());
  EXPECT_EQ(j.at("episodes"), 1234);
  EXPECT_EQ(j.at("objective_half_width"), 0.125);
  EXPECT_EQ(j.at("iterations"), 7);
  EXPECT_EQ(j.at("out"), "plan.json");
}

TEST(PlanSummary, TheTextHasOneLineEachAndNoDeliveredLineWithoutANetwork) {
  const Scenario scenario = defaultScenario();
  ASSERT_FALSE(scenario.network.has_value());
  PlanResult plan = madeUpPlan();
  plan.status = PlanStatus::Optimal;
  const PlanSummary s{plan, PlanSurrogate::Covariance, plan.bracket, false};
  const std::string text = planSummaryText(s, scenario, "default.yaml", "to standard output");
  const std::string expected_start =
      "scenario   default.yaml (n = " + std::to_string(scenario.stateDim()) +
      " states, M = " + std::to_string(scenario.sensorCount()) + " sensors, T = ";
  EXPECT_EQ(text.rfind(expected_start, 0), 0u) << text;
  EXPECT_NE(text.find("\nsurrogate  cov: objective 1.5, status optimal, 7 iterations in 0.250 s, "
                      "4 RK4 steps per interval\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("\nbracket    J(P_info) = 1.25 <= E[J] <= J(P_cov) = 2.5\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("delivered"), std::string::npos) << text;
  EXPECT_NE(text.find("\nwritten    to standard output\n"), std::string::npos) << text;
}

TEST(PlanSummary, TheDeliveredBracketIsThePlannedOneWithoutANetwork) {
  const Scenario scenario = defaultScenario();
  const CostBracket planned{1.0, 2.0};
  const CostBracket d =
      deliveredBracket(scenario, uniformSchedule(scenario), planned);  // no network: as planned
  EXPECT_EQ(d.info, 1.0);
  EXPECT_EQ(d.cov, 2.0);
}

TEST(PlanSummary, WithANetworkTheTextSaysWhatItDeliversAndWhetherItWasPlannedFor) {
  const Scenario lossy =
      loadScenarioFile(std::string(SENSORNET_SOURCE_DIR) + "/scenarios/lossy.yaml");
  ASSERT_TRUE(lossy.network.has_value());
  const PlanResult plan = madeUpPlan();
  const PlanSummary s{plan, PlanSurrogate::Information, {0.5, 4.0}, false};
  const std::string text = planSummaryText(s, lossy, "lossy.yaml", "plan.json");
  EXPECT_NE(text.find("\ndelivered  J(P_info) = 0.5 <= E[J] <= J(P_cov) = 4 (the network was not "
                      "planned for)\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("status failed: locally infeasible,"), std::string::npos) << text;
}

}  // namespace
}  // namespace sensornet
