// A schedule evaluated as `fusion_center evaluate` does (schedule_evaluation.hpp): the closed
// loop's paired gain is recomputed here from the two loops' episode costs; the open loop's
// numbers are those of the Monte Carlo called directly with the same seed (the promise that a
// sweep or Python gets the command's numbers); the episode costs written read back bit for bit.

#include "sensornet/evaluation/schedule_evaluation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

#include "../../support/scratch_dir.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/planning/planner.hpp"

namespace sensornet::evaluation {
namespace {

// Three states, four sensors, a non-symmetric drift (the paper's generator), T = 1.5, N = 6.
Scenario smallScenario() {
  return generateRandomScenario({.state_dim = 3, .sensor_count = 4, .seed = 3, .horizon_s = 1.5,
                                 .intervals = 6, .budget = 12.0});
}

double mean(const std::vector<double>& values) {
  return std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
}

TEST(ScheduleEvaluation, TheClosedLoopsGainIsThePairedDifferenceOfTheTwoLoops) {
  const Scenario scenario = smallScenario();
  const RateSchedule plan = uniformSchedule(scenario);
  ClosedLoopOptions loop;
  loop.replan_every_s = 0.5;
  loop.surrogate = PlanSurrogate::Information;
  loop.replanner.switch_margin_s = 0.05;
  loop.runs = 12;
  loop.seed = 17;
  loop.threads = 2;
  const ClosedLoopRun run = runClosedLoop(scenario, plan, loop);

  const std::vector<double> open = openLoopCosts(scenario, plan, loop.runs, loop.seed, 2);
  ASSERT_EQ(run.closed.episode_costs.size(), open.size());
  std::vector<double> differences;
  for (std::size_t e = 0; e < open.size(); ++e) {
    differences.push_back(run.closed.episode_costs[e] - open[e]);
  }
  EXPECT_NEAR(run.open_mean, mean(open), 1e-12 * mean(open));
  EXPECT_NEAR(run.gain.mean, mean(differences), 1e-12 * std::abs(mean(open)));
  EXPECT_GE(run.seconds, 0.0);
}

TEST(ScheduleEvaluation, TheOpenLoopIsTheMonteCarloOfTheSameSeed) {
  const Scenario scenario = smallScenario();
  const RateSchedule plan = uniformSchedule(scenario);
  MonteCarloOptions options;
  options.runs = 40;
  options.seed = 9;
  options.threads = 2;

  const OpenLoopRun poisson = runOpenLoop(scenario, plan, options, ArrivalMode::Poisson);
  EXPECT_FALSE(poisson.timetable.has_value());
  const MonteCarloResult direct = evaluateSchedule(scenario, plan, options);
  EXPECT_EQ(poisson.mc.mean, direct.mean);
  EXPECT_EQ(poisson.mc.ci95, direct.ci95);

  const OpenLoopRun timetable = runOpenLoop(scenario, plan, options, ArrivalMode::Timetable);
  ASSERT_TRUE(timetable.timetable.has_value());
  EXPECT_EQ(timetable.mc.mean, direct.mean);  // the Poisson mean stays the headline
  MonteCarloOptions fixed = options;
  fixed.arrivals = ArrivalMode::Timetable;
  EXPECT_EQ(timetable.timetable->mean, evaluateSchedule(scenario, plan, fixed).mean);
}

TEST(ScheduleEvaluation, EpisodeCostsReadBackBitForBit) {
  testing::ScratchDir dir;
  const std::vector<double> costs = {0.1, 1.0 / 3.0, 2.718281828459045, 1e-300, 12345.678901234567};
  writeEpisodeCosts(dir.file("costs.txt"), costs);
  std::ifstream in(dir.file("costs.txt"));
  std::vector<double> back;
  for (double c = 0.0; in >> c;) back.push_back(c);
  EXPECT_EQ(back, costs);
  EXPECT_THROW(writeEpisodeCosts(dir.file("no/such/folder/costs.txt"), costs), InputError);
}

}  // namespace
}  // namespace sensornet::evaluation
