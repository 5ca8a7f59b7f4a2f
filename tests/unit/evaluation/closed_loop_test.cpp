// The offline closed loop (evaluation::simulateClosedLoop): its instants, its pairing with the
// open loop, and one episode recomputed here step by step from the planner and the filter, so
// that the switch time, the covariance a tail is planned from and the schedule in force after
// it are checked against a computation that does not go through the Replanner or the book.

#include "sensornet/evaluation/closed_loop.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/poisson_arrivals.hpp"
#include "sensornet/core/surrogate.hpp"

namespace sensornet::evaluation {

using namespace sensornet::emulator;  // the coordinator's re-planner, as the live run uses it
namespace {

// Three states, four sensors, a non-symmetric drift (the paper's generator), T = 1.5, N = 6.
Scenario loopScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 4;
  spec.seed = 3;
  spec.horizon_s = 1.5;
  spec.intervals = 6;
  spec.budget = 12.0;
  return generateRandomScenario(spec);
}

RateSchedule infoPlan(const Scenario& s) {
  PlanRequest request;
  request.surrogate = PlanSurrogate::Information;
  return planSchedule(s, request).schedule;
}

ClosedLoopOptions loopOptions(double every, int runs) {
  ClosedLoopOptions options;
  options.replan_every_s = every;
  options.surrogate = PlanSurrogate::Information;
  options.replanner.switch_margin_s = 0.05;
  options.replanner.time_scale = 1.0;
  options.runs = runs;
  options.seed = 17;
  options.threads = 2;
  return options;
}

TEST(ClosedLoopInstants, AreTheMultiplesOfTheCadenceBelowTheHorizon) {
  EXPECT_EQ(replanInstants(1.0, 3.0), (std::vector<double>{1.0, 2.0}));
  const std::vector<double> odd = replanInstants(0.7, 3.0);
  ASSERT_EQ(odd.size(), 4u);
  EXPECT_DOUBLE_EQ(odd.back(), 2.8);
  EXPECT_TRUE(replanInstants(3.0, 3.0).empty());
  EXPECT_TRUE(replanInstants(5.0, 3.0).empty());
  EXPECT_THROW((void)replanInstants(0.0, 3.0), InputError);
  EXPECT_THROW((void)replanInstants(std::nan(""), 3.0), InputError);
}

TEST(ClosedLoop, WithNoInstantInTheHorizonItIsTheOpenLoopBitForBit) {
  const Scenario s = loopScenario();
  const RateSchedule plan = infoPlan(s);
  const ClosedLoopResult closed = simulateClosedLoop(s, plan, loopOptions(10.0, 200));
  const std::vector<double> open = openLoopCosts(s, plan, 200, 17, 1);
  ASSERT_EQ(closed.episode_costs.size(), open.size());
  for (std::size_t e = 0; e < open.size(); ++e) EXPECT_EQ(closed.episode_costs[e], open[e]) << e;
  EXPECT_EQ(closed.tails_mean, 0.0);
}

TEST(ClosedLoop, EveryInstantWithRoomForASwitchPublishesATailAndThreadsChangeNothing) {
  const Scenario s = loopScenario();
  const RateSchedule plan = infoPlan(s);
  ClosedLoopOptions options = loopOptions(0.4, 40);  // instants 0.4, 0.8, 1.2; switches < 1.5
  const ClosedLoopResult two = simulateClosedLoop(s, plan, options);
  EXPECT_EQ(two.tails_mean, 3.0);
  EXPECT_EQ(two.refused, 0);
  options.threads = 1;
  const ClosedLoopResult one = simulateClosedLoop(s, plan, options);
  EXPECT_EQ(one.episode_costs, two.episode_costs);
  // Feedback changes the cost of (nearly) every episode.
  const std::vector<double> open = openLoopCosts(s, plan, 40, 17, 2);
  int changed = 0;
  for (std::size_t e = 0; e < open.size(); ++e) changed += open[e] != two.episode_costs[e] ? 1 : 0;
  EXPECT_GE(changed, 30);
}

// Episode 3 of seed 17 with one instant at 0.6 s, recomputed: the filter runs to 0.6 under the
// open-loop plan; the covariance is carried to the switch tick by the information form under
// that plan; the planner plans [switch, T] from it, warm-started at the schedule in force; the
// filter goes on under the open-loop plan to the switch and under the tail after it.
TEST(ClosedLoop, AnEpisodeEqualsTheFilterUnderThePlannersTailFromTheSwitchTick) {
  const Scenario s = loopScenario();
  const RateSchedule open_loop = infoPlan(s);
  const ClosedLoopOptions options = loopOptions(0.6, 4);  // instants 0.6 and 1.2
  const ClosedLoopResult closed = simulateClosedLoop(s, open_loop, options);

  const EmulatedPlant plant(s, options.seed);
  const double margin = options.replanner.switch_margin_s * options.replanner.time_scale;
  const int episode = 3;
  TimeChangedArrivals arrivals(s.sensorCount(), options.seed, episode);
  CdKalmanFilter filter(s);
  std::vector<Arrival> piece;
  const auto fuse = [&](const RateSchedule& schedule, double to) {
    arrivals.drawUntil(schedule, to, piece);
    for (const Arrival& a : piece) {
      filter.propagateTo(a.time);
      filter.updateCovariance(a.sensor);
    }
    filter.propagateTo(to);
  };
  RateSchedule in_force = open_loop;
  for (const double instant : {0.6, 1.2}) {
    fuse(in_force, instant);
    const double at = plant.timeOf(plant.tickAt(instant + margin));
    RolloutOptions carry;
    carry.start_time = instant;
    carry.end_time = at;
    carry.start_covariance = filter.covariance();
    PlanRequest request;
    request.surrogate = PlanSurrogate::Information;
    request.start_time = at;
    request.start_covariance = rolloutInformationForm(s, in_force, carry).covariances.back();
    request.warm_start = in_force;  // the schedule in force: its rates before the switch stay
    request.max_seconds = options.replanner.max_plan_seconds;
    const PlanResult tail = planSchedule(s, request);
    ASSERT_EQ(tail.status, PlanStatus::Optimal) << "at " << instant;
    fuse(in_force, at);
    in_force = tail.schedule;
  }
  fuse(in_force, s.horizon_s);
  EXPECT_NEAR(closed.episode_costs[episode], filter.cost(), 1e-12 * filter.cost());
}

TEST(ClosedLoop, RefusesOptionsOutOfRange) {
  const Scenario s = loopScenario();
  const RateSchedule plan = infoPlan(s);
  ClosedLoopOptions options = loopOptions(0.5, 10);
  options.surrogate = PlanSurrogate::Uniform;
  EXPECT_THROW((void)simulateClosedLoop(s, plan, options), InputError);
  options = loopOptions(0.5, 0);
  EXPECT_THROW((void)simulateClosedLoop(s, plan, options), InputError);
  options = loopOptions(-1.0, 10);
  EXPECT_THROW((void)simulateClosedLoop(s, plan, options), InputError);
  const RateSchedule short_plan(1.0, plan.rates());
  EXPECT_THROW((void)simulateClosedLoop(s, short_plan, loopOptions(0.5, 10)), InputError);
}

// With energy budgets of 2, 3, 4 and 5 expected measurements per episode (14 in all, against
// the 18 that the rate budget alone allows), each tail may spend only what the schedule in force
// left, so an episode's expected count is at most 14 and its realized count is Poisson with
// that mean or less. The mean count over 400 episodes exceeds 14 + 4 standard errors
// (sqrt(14 / 400)) with probability below 4e-5; a tail that spent its whole budget again would
// add about one budget's worth of the rest of the episode per sensor.
TEST(ClosedLoop, TailsSpendOnlyTheEnergyTheScheduleInForceLeft) {
  Scenario s = loopScenario();
  s.constraints.energy = (Eigen::VectorXd(4) << 2.0, 3.0, 4.0, 5.0).finished();
  validateScenario(s, "test");
  const RateSchedule plan = infoPlan(s);
  ASSERT_TRUE(checkFeasibility(plan, s).feasible);
  const ClosedLoopResult closed = simulateClosedLoop(s, plan, loopOptions(0.4, 400));
  EXPECT_EQ(closed.tails_mean, 3.0);
  EXPECT_EQ(closed.refused, 0);
  EXPECT_LE(closed.arrivals_mean, 14.0 + 4.0 * std::sqrt(14.0 / 400.0));
  // The budgets bind: the open-loop plan spends them all, and so does the loop on average.
  EXPECT_NEAR(plan.expectedCounts(0.0, s.horizon_s).sum(), 14.0, 1e-6);
  EXPECT_GE(closed.arrivals_mean, 14.0 - 4.0 * std::sqrt(14.0 / 400.0));
}

}  // namespace
}  // namespace sensornet::evaluation
