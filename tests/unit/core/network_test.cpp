#include "sensornet/core/network.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "sensornet/core/input_error.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/planning/surrogate_transcription.hpp"
#include "support/eigen_near.hpp"

namespace sensornet {
namespace {

// T = 3, N = 30, two sensors: λ_0 = 1 + 0.1 k and λ_1 = 2 + 0.1 k on interval k.
RateSchedule rampSchedule() {
  Eigen::MatrixXd rates(30, 2);
  for (int k = 0; k < 30; ++k) {
    rates(k, 0) = 1.0 + 0.1 * k;
    rates(k, 1) = 2.0 + 0.1 * k;
  }
  return RateSchedule(3.0, rates);
}

NetworkSpec lossEverywhere(double loss, int sensors) {
  NetworkSpec network;
  network.links.assign(static_cast<std::size_t>(sensors), LinkSpec{});
  for (LinkSpec& link : network.links) link.loss = loss;
  return network;
}

Outage outage(int sensor, double from_s, double to_s, std::vector<std::uint32_t> episodes = {}) {
  Outage o;
  o.sensor = sensor;
  o.from_s = from_s;
  o.to_s = to_s;
  o.episodes = std::move(episodes);
  return o;
}

TEST(DeliveredSchedule, ExpectedCountsAreThinnedByLossAndCutByTheOutage) {
  NetworkSpec network = lossEverywhere(0.3, 2);
  network.outages.push_back(outage(0, 0.5, 1.2));
  const RateSchedule delivered = deliveredSchedule(rampSchedule(), network, 0);
  const Eigen::VectorXd counts = delivered.expectedCounts(0.0, 3.0);
  // By hand: ∫λ_0 = 0.1 Σ_{k<30} (1 + 0.1 k) = 0.1 (30 + 43.5) = 7.35; the outage covers
  // intervals 5..11, 0.1 (7 + 0.1 (5 + ... + 11)) = 0.1 (7 + 5.6) = 1.26; so 0.7 (7.35 - 1.26).
  EXPECT_NEAR(counts(0), 0.7 * 6.09, 1e-12);
  // ∫λ_1 = 0.1 (60 + 43.5) = 10.35, no outage.
  EXPECT_NEAR(counts(1), 0.7 * 10.35, 1e-12);
  EXPECT_NEAR(delivered.expectedCounts(0.5, 1.2)(0), 0.0, 1e-15);
  // Just before the outage the rate is the thinned one: 0.7 (1 + 0.1 * 4) on [0.4, 0.5).
  EXPECT_NEAR(delivered.expectedCounts(0.4, 0.5)(0), 0.7 * 1.4 * 0.1, 1e-12);
  EXPECT_EQ(delivered.intervals(), 30);
  EXPECT_DOUBLE_EQ(delivered.horizon(), 3.0);
}

TEST(DeliveredSchedule, WithoutNetworkItIsTheScheduleItself) {
  const RateSchedule schedule = rampSchedule();
  const RateSchedule delivered = deliveredSchedule(schedule, NetworkSpec{}, 4);
  EXPECT_EQ(delivered.rates(), schedule.rates());
}

TEST(DeliveredSchedule, RefinesTheGridSoThatEveryOutageEdgeIsOnIt) {
  const RateSchedule schedule(1.0, Eigen::MatrixXd::Constant(10, 1, 4.0));
  NetworkSpec network;
  network.outages.push_back(outage(0, 0.25, 0.75));  // 0.25 on a 0.1 grid: factor 2
  const RateSchedule delivered = deliveredSchedule(schedule, network, 0);
  EXPECT_EQ(delivered.intervals(), 20);
  // 4 Hz over the half of [0, 1] outside the outage.
  EXPECT_NEAR(delivered.expectedCounts(0.0, 1.0)(0), 2.0, 1e-12);
  EXPECT_NEAR(delivered.expectedCounts(0.2, 0.3)(0), 4.0 * 0.05, 1e-12);
}

TEST(OutageRefinement, IsTheSmallestFactorPuttingEveryEdgeOnTheGrid) {
  EXPECT_EQ(outageRefinement(3.0, 30, {outage(0, 0.5, 1.2)}), 1);
  EXPECT_EQ(outageRefinement(1.0, 10, {outage(0, 0.25, 0.5)}), 2);
  EXPECT_EQ(outageRefinement(1.0, 10, {outage(0, 0.25, 0.5), outage(1, 0.0, 1.0 / 3.0)}), 6);
  EXPECT_EQ(outageRefinement(1.0, 10, {outage(0, 0.1233, 0.5)}), 1000);
  EXPECT_EQ(outageRefinement(1.0, 10, {outage(0, 0.1234, 0.5)}), 500);
  EXPECT_EQ(outageRefinement(1.0, 10, {outage(0, std::sqrt(2.0) / 10.0, 0.5)}), 0);
  EXPECT_EQ(outageRefinement(1.0, 10, {}), 1);
}

TEST(DeliveredSchedule, OutageOfOtherEpisodesHasNoEffect) {
  NetworkSpec network = lossEverywhere(0.3, 2);
  network.outages.push_back(outage(0, 0.5, 1.2, {1, 2}));
  const RateSchedule in_episode_0 = deliveredSchedule(rampSchedule(), network, 0);
  EXPECT_NEAR(in_episode_0.expectedCounts(0.0, 3.0)(0), 0.7 * 7.35, 1e-12);
  const RateSchedule in_episode_2 = deliveredSchedule(rampSchedule(), network, 2);
  EXPECT_NEAR(in_episode_2.expectedCounts(0.0, 3.0)(0), 0.7 * 6.09, 1e-12);
}

TEST(Outage, AppliesToItsEpisodesOrToAllWhenNoneAreListed) {
  EXPECT_TRUE(outage(0, 0, 1).appliesTo(7));
  const Outage listed = outage(0, 0, 1, {1, 3});
  EXPECT_TRUE(listed.appliesTo(3));
  EXPECT_FALSE(listed.appliesTo(2));
}

Scenario tenIntervalScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 2;
  spec.sensor_count = 2;
  spec.intervals = 10;
  spec.horizon_s = 1.0;
  return generateRandomScenario(spec);
}

TEST(DeliveryFactors, AreOneWithoutNetwork) {
  const Scenario s = tenIntervalScenario();
  EXPECT_EQ(deliveryFactors(s), Eigen::MatrixXd::Ones(10, 2));
}

TEST(DeliveryFactors, AreTheDeliveredFractionOfEachInterval) {
  Scenario s = tenIntervalScenario();
  NetworkSpec network = lossEverywhere(0.0, 2);
  network.links[0].loss = 0.2;
  network.outages.push_back(outage(0, 0.25, 0.75));
  network.outages.push_back(outage(0, 0.3, 0.5));       // overlaps the first: counted once
  network.outages.push_back(outage(1, 0.0, 0.5, {0}));  // one episode only: not planned for
  s.network = network;
  const Eigen::MatrixXd f = deliveryFactors(s);
  ASSERT_EQ(f.rows(), 10);
  ASSERT_EQ(f.cols(), 2);
  EXPECT_NEAR(f(0, 0), 0.8, 1e-12);
  EXPECT_NEAR(f(2, 0), 0.8 * 0.5, 1e-12);  // [0.2, 0.3): half of it down
  EXPECT_NEAR(f(3, 0), 0.0, 1e-12);
  EXPECT_NEAR(f(7, 0), 0.8 * 0.5, 1e-12);
  EXPECT_NEAR(f(8, 0), 0.8, 1e-12);
  EXPECT_EQ(f.col(1), Eigen::VectorXd::Ones(10));
}

// Network-aware planning (PlanRequest::delivery): the surrogate sees delivery ⊙ λ while C λ <= b
// binds λ.

Scenario planningScenario(std::uint64_t seed = 3) {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 4;
  spec.intervals = 10;
  spec.horizon_s = 2.0;
  spec.budget = 6.0;  // one budget row 1'λ <= 6
  spec.seed = seed;
  return generateRandomScenario(spec);
}

NetworkSpec withLoss(const Scenario& s, const std::vector<double>& loss) {
  NetworkSpec network = lossEverywhere(0.0, s.sensorCount());
  for (std::size_t j = 0; j < loss.size(); ++j) network.links[j].loss = loss[j];
  return network;
}

CostBracket deliveredBracket(const Scenario& s, const RateSchedule& plan,
                             const NetworkSpec& network) {
  return computeBracket(s, deliveredSchedule(plan, network, 0));
}

// Central differences of the transcription's cost in λ, against its adjoint gradient with the
// chain rule through the delivery factors (step 1e-5: truncation and rounding far below 1e-6).
TEST(NetworkAwareTranscription, GradientIsTheDeliveryTimesTheGradientInDeliveredRates) {
  const Scenario s = planningScenario();
  Rng rng = Rng::keyed(5, 11);
  Eigen::MatrixXd delivery(s.intervals, s.sensorCount());
  Eigen::MatrixXd rates(s.intervals, s.sensorCount());
  for (int k = 0; k < s.intervals; ++k) {
    for (int j = 0; j < s.sensorCount(); ++j) {
      delivery(k, j) = 0.2 + 0.8 * rng.uniform();
      rates(k, j) = 0.3 + 2.0 * rng.uniform();
    }
  }
  for (const auto form : {SurrogateForm::Information, SurrogateForm::Covariance}) {
    TranscriptionOptions options;
    options.delivery = delivery;
    SurrogateTranscription aware(form, s, options);
    SurrogateTranscription plain(form, s);
    // The cost is the plain cost at the delivered rates.
    EXPECT_EQ(aware.cost(rates), plain.cost(rates.cwiseProduct(delivery)));
    const CostGradient cg = aware.costAndGradient(rates);
    Eigen::MatrixXd fd(rates.rows(), rates.cols());
    for (int k = 0; k < rates.rows(); ++k) {
      for (int j = 0; j < rates.cols(); ++j) {
        const double step = 1e-5 * std::max(1.0, rates(k, j));
        Eigen::MatrixXd plus = rates, minus = rates;
        plus(k, j) += step;
        minus(k, j) -= step;
        fd(k, j) = (aware.cost(plus) - aware.cost(minus)) / (2.0 * step);
      }
    }
    // In units of the largest finite difference: every entry within 1e-6 of it.
    const double scale = fd.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    EXPECT_MATRIX_NEAR(cg.gradient / scale, fd / scale, 1e-6)
        << "adjoint against finite differences";
  }
}

TEST(NetworkAwarePlanning, FactorsOfOneChangeNothing) {
  const Scenario s = planningScenario();
  PlanRequest plain;
  PlanRequest ones = plain;
  ones.delivery = Eigen::MatrixXd::Ones(s.intervals, s.sensorCount());
  const PlanResult a = planSchedule(s, plain);
  const PlanResult b = planSchedule(s, ones);
  EXPECT_EQ(a.schedule.rates(), b.schedule.rates());
  EXPECT_EQ(a.objective, b.objective);
}

TEST(NetworkAwarePlanning, UniformLossPlanDeliversNoWorseBracketThanThePlainPlan) {
  const Scenario s = planningScenario();
  for (const double p : {0.3, 0.6}) {
    const NetworkSpec network = withLoss(s, std::vector<double>(4, p));
    Scenario lossy = s;
    lossy.network = network;
    for (const auto surrogate : {PlanSurrogate::Information, PlanSurrogate::Covariance}) {
      PlanRequest request;
      request.surrogate = surrogate;
      const PlanResult plain = planSchedule(s, request);
      request.delivery = deliveryFactors(lossy);
      const PlanResult aware = planSchedule(s, request);
      EXPECT_TRUE(checkFeasibility(aware.schedule, s).feasible);
      const CostBracket plain_delivered = deliveredBracket(s, plain.schedule, network);
      const CostBracket aware_delivered = deliveredBracket(s, aware.schedule, network);
      // Each plan is judged by the surrogate it minimized; 1e-4 relative covers the planner's
      // RK4 transcription (it optimizes a cost within O(h^4) of the accurate one).
      const bool info = surrogate == PlanSurrogate::Information;
      const double plain_cost = info ? plain_delivered.info : plain_delivered.cov;
      const double aware_cost = info ? aware_delivered.info : aware_delivered.cov;
      EXPECT_LE(aware_cost, plain_cost * (1.0 + 1e-4)) << "p = " << p;
      // With uniform loss the planner's objective is the delivered cost itself.
      EXPECT_NEAR(aware.objective, aware_cost, 1e-8 * aware_cost);
    }
  }
}

TEST(NetworkAwarePlanning, ALossyLinkGetsLessRateThanInThePlainPlan) {
  const Scenario s = planningScenario();
  Scenario lossy = s;
  lossy.network = withLoss(s, {0.9});
  for (const PlanMethod method : {PlanMethod::ProjectedGradient, PlanMethod::Ipopt}) {
    PlanRequest request;
    request.method = method;
    const PlanResult plain = planSchedule(s, request);
    request.delivery = deliveryFactors(lossy);
    const PlanResult aware = planSchedule(s, request);
    const double plain_rate = plain.schedule.rates().col(0).sum();
    const double aware_rate = aware.schedule.rates().col(0).sum();
    EXPECT_GT(plain_rate, 0.5) << "the plain plan uses sensor 0, so the test can fail";
    EXPECT_LT(aware_rate, 0.8 * plain_rate) << (method == PlanMethod::Ipopt ? "ipopt" : "pqn");
    const CostBracket plain_delivered = deliveredBracket(s, plain.schedule, *lossy.network);
    const CostBracket aware_delivered = deliveredBracket(s, aware.schedule, *lossy.network);
    EXPECT_LE(aware_delivered.info, plain_delivered.info * (1.0 + 1e-4));
  }
}

TEST(NetworkAwarePlanning, RefusesDeliveryFactorsThatDoNotFit) {
  const Scenario s = planningScenario();
  PlanRequest request;
  request.delivery = Eigen::MatrixXd::Ones(3, 4);
  EXPECT_THROW((void)planSchedule(s, request), InputError);
  request.delivery = Eigen::MatrixXd::Constant(s.intervals, s.sensorCount(), 1.5);
  EXPECT_THROW((void)planSchedule(s, request), InputError);
}

// A sensor dead from 1.25 s of the ramp: by hand, ∫_0^1.25 (1 + 0.1 k) over intervals 0..11
// (0.1 (12 + 6.6) = 1.86) plus half of interval 12 (0.05 * 2.2 = 0.11) is 1.97, and nothing
// after; the other sensor keeps its 10.35; one dead before the episode (0) delivers nothing.
TEST(SilencedSchedule, ADeadSensorDeliversNothingFromItsDeath) {
  const RateSchedule ramp = rampSchedule();
  const RateSchedule from_death = silencedSchedule(ramp, {1.25, std::nullopt});
  EXPECT_NEAR(from_death.expectedCounts(0.0, 3.0)(0), 1.97, 1e-12);
  EXPECT_NEAR(from_death.expectedCounts(1.3, 3.0)(0), 0.0, 1e-15);
  EXPECT_NEAR(from_death.expectedCounts(0.0, 3.0)(1), 10.35, 1e-12);
  EXPECT_DOUBLE_EQ(from_death.rate(11, 0), ramp.rate(11, 0));
  const RateSchedule dead_before = silencedSchedule(ramp, {std::nullopt, 0.0});
  EXPECT_EQ(dead_before.rates().col(1).norm(), 0.0);
  EXPECT_EQ(dead_before.rates().col(0), ramp.rates().col(0));
  // A list shorter than the sensors leaves the rest as they are.
  EXPECT_EQ(silencedSchedule(ramp, {}).rates(), ramp.rates());
}

}  // namespace
}  // namespace sensornet
