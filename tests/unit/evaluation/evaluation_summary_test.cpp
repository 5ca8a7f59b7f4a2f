// What `fusion_center evaluate` says of its runs, from results made up here (no simulation):
// whether the interval meets the bracket, the closed loop's surrogate when none is given, the
// verdict of the paired difference, and the fields and lines of both summaries.
#include "sensornet/evaluation/evaluation_summary.hpp"

#include <gtest/gtest.h>

#include "sensornet/core/input_error.hpp"

#include <string>

#include "sensornet/io/scenario_file.hpp"

namespace sensornet::evaluation {

using namespace sensornet::emulator;  // the coordinator's re-planner, as the live run uses it
namespace {

Scenario defaultScenario() {
  return loadScenarioFile(std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml");
}

MonteCarloResult madeUpMc(double mean, double ci95) {
  MonteCarloResult mc;
  mc.runs = 100;
  mc.mean = mean;
  mc.ci95 = ci95;
  mc.std_dev = 2.0;
  mc.nees_mean = 1.5;
  mc.squared_error_mean = 0.25;
  mc.arrivals_mean = 42.0;
  return mc;
}

TEST(EvaluationSummary, TheIntervalMeetsTheBracketWhenTheyOverlap) {
  const CostBracket bracket{10.0, 20.0};
  EXPECT_TRUE(meetsBracket(madeUpMc(15.0, 1.0), bracket));
  EXPECT_TRUE(meetsBracket(madeUpMc(21.0, 1.0), bracket));   // touches cov
  EXPECT_TRUE(meetsBracket(madeUpMc(9.0, 1.0), bracket));    // touches info
  EXPECT_FALSE(meetsBracket(madeUpMc(21.5, 1.0), bracket));  // above
  EXPECT_FALSE(meetsBracket(madeUpMc(8.5, 1.0), bracket));   // below
}

TEST(EvaluationSummary, TheClosedLoopPlansWithTheFlagElseTheFilesInfoOrCovElseCov) {
  EXPECT_EQ(closedLoopSurrogate("info", R"({"surrogate": "cov"})"), PlanSurrogate::Information);
  EXPECT_EQ(closedLoopSurrogate("", R"({"surrogate": "info"})"), PlanSurrogate::Information);
  EXPECT_EQ(closedLoopSurrogate("", R"({"surrogate": "uniform"})"), PlanSurrogate::Covariance);
  EXPECT_THROW((void)closedLoopSurrogate("uniform", ""), InputError);  // the loop cannot plan it
  EXPECT_THROW((void)closedLoopSurrogate("nonsense", ""), InputError);
  EXPECT_EQ(closedLoopSurrogate("", R"({"surrogate": "file"})"), PlanSurrogate::Covariance);
  EXPECT_EQ(closedLoopSurrogate("", "not json"), PlanSurrogate::Covariance);
  EXPECT_EQ(closedLoopSurrogate("", ""), PlanSurrogate::Covariance);
}

TEST(EvaluationSummary, TheVerdictIsWhereThePairedIntervalLiesAgainstZero) {
  EXPECT_STREQ(feedbackVerdict({-1.0, 0.0, 0.5}), "feedback pays");
  EXPECT_STREQ(feedbackVerdict({1.0, 0.0, 0.5}), "feedback costs");
  EXPECT_STREQ(feedbackVerdict({0.25, 0.0, 0.5}), "no difference at this sample size");
}

TEST(EvaluationSummary, TheOpenLoopSaysTheTimetableOnlyWithTimetableArrivals) {
  const Scenario scenario = defaultScenario();
  const MonteCarloResult mc = madeUpMc(15.0, 1.0);
  const MonteCarloResult timetable = madeUpMc(14.0, 0.0);
  OpenLoopEvaluation e{scenario,
                       "default.yaml",
                       "uniform",
                       {10.0, 20.0},
                       mc,
                       nullptr,
                       ArrivalMode::Poisson,
                       false,
                       7,
                       1.5};
  nlohmann::json doc = evaluationJson(e);
  EXPECT_TRUE(doc.at("timetable").is_null());
  EXPECT_TRUE(doc.at("nees").is_null());  // no simulated plant
  EXPECT_EQ(doc.at("arrivals"), "poisson");
  EXPECT_EQ(doc.at("meets_bracket"), true);
  EXPECT_EQ(doc.at("seed"), 7);
  std::string text = evaluationText(e);
  EXPECT_NE(text.find("\nschedule  uniform\n"), std::string::npos) << text;
  EXPECT_NE(text.find("the 95% interval meets the bracket"), std::string::npos) << text;
  EXPECT_EQ(text.find("timetable"), std::string::npos) << text;
  EXPECT_EQ(text.find("NEES"), std::string::npos) << text;

  e.timetable = &timetable;
  e.mode = ArrivalMode::Timetable;
  e.simulate_plant = true;
  doc = evaluationJson(e);
  EXPECT_EQ(doc.at("timetable").at("minus_poisson_mean"), -1.0);
  EXPECT_EQ(doc.at("nees"), 1.5);
  text = evaluationText(e);
  EXPECT_NE(text.find("timetable  J = 14 (std over episodes 2), 42 arrivals per episode\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("minus the Poisson mean: -1 (Poisson 95% half-width 1)\n"), std::string::npos)
      << text;
}

TEST(EvaluationSummary, TheClosedLoopSaysItsSurrogateMarginAndVerdict) {
  const Scenario scenario = defaultScenario();
  ClosedLoopResult closed;
  closed.runs = 50;
  closed.mean = 12.0;
  closed.tails_mean = 2.5;
  closed.refused = 3;
  const ClosedLoopEvaluation e{scenario,
                               "default.yaml",
                               "plan.json",
                               {10.0, 20.0},
                               closed,
                               13.0,
                               {-1.0, 0.0, 0.5},
                               PlanSurrogate::Information,
                               0.5,
                               0.3,
                               1,
                               2.0};
  const nlohmann::json doc = closedLoopJson(e);
  EXPECT_EQ(doc.at("closed_loop").at("surrogate"), "info");
  EXPECT_EQ(doc.at("closed_loop").at("refused"), 3);
  EXPECT_EQ(doc.at("open_loop").at("mean"), 13.0);
  EXPECT_EQ(doc.at("schedule"), "plan.json");
  const std::string text = closedLoopText(e);
  EXPECT_NE(text.find("closed loop  re-plan with info every 0.5 s, each tail from 0.3 s later; "
                      "2.50 tails per episode, 3 refused\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find(": feedback pays\n"), std::string::npos) << text;
}

}  // namespace
}  // namespace sensornet::evaluation
