// The planner's request from the user's choices (plan_request.hpp): what the scenario cannot
// take is bad input named before any solve, the Monte Carlo planner's default time limit, and
// the network's delivery factors for --network-aware.

#include "sensornet/io/plan_request.hpp"

#include <gtest/gtest.h>

#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet {
namespace {

const std::string kDefault = std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml";
const std::string kLossy = std::string(SENSORNET_SOURCE_DIR) + "/scenarios/lossy.yaml";

TEST(PlanRequest, ChoicesReachTheRequest) {
  const Scenario scenario = loadScenarioFile(kDefault);
  PlanChoices choices;
  choices.surrogate = PlanSurrogate::Information;
  choices.method = PlanMethod::Ipopt;
  choices.tolerance = 1e-7;
  choices.max_iterations = 42;
  choices.excluded = {0, scenario.sensorCount() - 1};
  const PlanRequest request = planRequest(scenario, kDefault, choices);
  EXPECT_EQ(request.surrogate, PlanSurrogate::Information);
  EXPECT_EQ(request.method, PlanMethod::Ipopt);
  EXPECT_EQ(request.tolerance, 1e-7);
  EXPECT_EQ(request.max_iterations, 42);
  EXPECT_EQ(request.max_seconds, 120.0);
  EXPECT_EQ(request.excluded_sensors, choices.excluded);
  EXPECT_FALSE(request.delivery.has_value());
}

TEST(PlanRequest, MonteCarloGetsItsOwnLimitUnlessOneIsGiven) {
  const Scenario scenario = loadScenarioFile(kDefault);
  PlanChoices choices;
  choices.surrogate = PlanSurrogate::MonteCarlo;
  EXPECT_EQ(planRequest(scenario, kDefault, choices).max_seconds, kMonteCarloPlanSeconds);
  choices.max_seconds = 7.0;
  choices.max_seconds_given = true;
  EXPECT_EQ(planRequest(scenario, kDefault, choices).max_seconds, 7.0);
}

TEST(PlanRequest, ASensorTheScenarioDoesNotHaveIsRefused) {
  const Scenario scenario = loadScenarioFile(kDefault);
  PlanChoices choices;
  choices.excluded = {scenario.sensorCount()};
  try {
    (void)planRequest(scenario, kDefault, choices);
    FAIL() << "an excluded sensor past the last one was accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--exclude"), std::string::npos) << message;
    EXPECT_NE(message.find(std::to_string(scenario.sensorCount())), std::string::npos) << message;
  }
  choices.excluded = {-1};
  EXPECT_THROW((void)planRequest(scenario, kDefault, choices), InputError);
}

TEST(PlanRequest, NetworkAwareNeedsANetworkAndPlansForWhatItDelivers) {
  PlanChoices choices;
  choices.network_aware = true;
  try {
    (void)planRequest(loadScenarioFile(kDefault), kDefault, choices);
    FAIL() << "--network-aware was accepted without a network: section";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(kDefault), std::string::npos) << e.what();
  }
  const Scenario lossy = loadScenarioFile(kLossy);
  const PlanRequest request = planRequest(lossy, kLossy, choices);
  ASSERT_TRUE(request.delivery.has_value());
  EXPECT_TRUE(request.delivery->isApprox(deliveryFactors(lossy)));
  EXPECT_LT(request.delivery->maxCoeff(), 1.0 + 1e-12);
  EXPECT_LT(request.delivery->minCoeff(), 1.0);  // the lossy network thins some rate
}

}  // namespace
}  // namespace sensornet
