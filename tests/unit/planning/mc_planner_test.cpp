#include "sensornet/planning/mc_planner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/core/student_t.hpp"

namespace sensornet {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// A scalar state that neither moves nor diffuses (A = Q = 0), W = 0, W_T = 1, two sensors with
// H = 1 and noise variances r_j: P(T) = 1 / (1/P0 + k_1/r_1 + k_2/r_2) depends only on the
// arrival counts k_j ~ Poisson(Λ_j), so E[J] and its rate derivatives are exact sums.
Scenario staticScalar(int intervals) {
  Scenario s;
  s.horizon_s = 2.0;
  s.intervals = intervals;
  s.plant.A = MatrixXd::Zero(1, 1);
  s.plant.Q = MatrixXd::Zero(1, 1);
  s.plant.P0 = MatrixXd::Constant(1, 1, 4.0);
  for (double r : {0.5, 2.0}) s.sensors.push_back({MatrixXd::Ones(1, 1), MatrixXd::Constant(1, 1, r)});
  s.cost.W = MatrixXd::Zero(1, 1);
  s.cost.WT = MatrixXd::Ones(1, 1);
  s.constraints.C = MatrixXd::Ones(1, 2);
  s.constraints.b = VectorXd::Constant(1, 3.0);
  return s;
}

double poisson(int k, double mean) {
  return std::exp(k * std::log(std::max(mean, 1e-300)) - mean - std::lgamma(k + 1.0)) *
         (k == 0 || mean > 0.0 ? 1.0 : 0.0);
}

// E[g(k_1, k_2)] for independent Poisson counts with the given means (truncated at 80 each).
double expectation(double mean1, double mean2, const std::function<double(int, int)>& g) {
  double sum = 0.0;
  for (int a = 0; a < 80; ++a)
    for (int b = 0; b < 80; ++b) sum += poisson(a, mean1) * poisson(b, mean2) * g(a, b);
  return sum;
}

double staticCost(const Scenario& s, int a, int b) {
  return 1.0 / (1.0 / s.plant.P0(0, 0) + a / s.sensors[0].R(0, 0) + b / s.sensors[1].R(0, 0));
}

double meanOf(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

double stdErrorOf(const std::vector<double>& v) {
  const double m = meanOf(v);
  double sq = 0.0;
  for (double x : v) sq += (x - m) * (x - m);
  const auto n = static_cast<double>(v.size());
  return std::sqrt(sq / (n - 1.0) / n);
}

TEST(RealizedCostSampler, MeanCostMatchesTheExactPoissonSum) {
  const Scenario s = staticScalar(2);
  MatrixXd rates(2, 2);
  rates << 1.0, 0.0, 0.5, 2.0;
  PlanRequest request;
  const RealizedCostSampler sampler(s, request, 2);
  const std::vector<double> costs = sampler.episodeCosts(rates, 11, 0, 20000);
  const double exact = expectation(1.0 * 1.0 + 0.5 * 1.0, 2.0 * 1.0,
                                   [&](int a, int b) { return staticCost(s, a, b); });
  // Two-sided false-alarm rate 1e-5 (|z| > 4.42); the seed is fixed.
  EXPECT_NEAR(meanOf(costs), exact, 4.42 * stdErrorOf(costs));
}

// Batch estimates of the gradient over 20 seeds, compared with `exact` by a t-test on the batch
// means (two-sided false-alarm rate 1e-3 per entry: |t| > t_{0.9995, 19} = 3.88).
void expectGradientMatches(const Scenario& s, const MatrixXd& rates, const MatrixXd& exact,
                           int sensors) {
  PlanRequest request;
  const RealizedCostSampler sampler(s, request, 2);
  std::vector<MatrixXd> batches;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    batches.push_back(sampler.gradient(rates, seed, 400, {0, 1}, sensors).gradient);
  }
  const double t = studentTQuantile(0.9995, 19.0);
  for (int k = 0; k < rates.rows(); ++k) {
    for (int j = 0; j < rates.cols(); ++j) {
      std::vector<double> values;
      for (const MatrixXd& g : batches) values.push_back(g(k, j));
      EXPECT_NEAR(meanOf(values), exact(k, j), t * stdErrorOf(values) + 1e-12)
          << "entry (" << k << ", " << j << ") at rate " << rates(k, j);
    }
  }
}

MatrixXd exactStaticGradient(const Scenario& s, const MatrixXd& rates) {
  const double h = s.intervalLength();
  const double mean1 = rates.col(0).sum() * h;
  const double mean2 = rates.col(1).sum() * h;
  const double d1 = expectation(mean1, mean2, [&](int a, int b) {
    return staticCost(s, a + 1, b) - staticCost(s, a, b);
  });
  const double d2 = expectation(mean1, mean2, [&](int a, int b) {
    return staticCost(s, a, b + 1) - staticCost(s, a, b);
  });
  MatrixXd exact(rates.rows(), rates.cols());
  for (int k = 0; k < rates.rows(); ++k) exact.row(k) << h * d1, h * d2;
  return exact;
}

TEST(RealizedCostSampler, AddOnePointGradientIsExactAlsoAtZeroRate) {
  const Scenario s = staticScalar(2);
  MatrixXd rates(2, 2);
  rates << 0.0, 0.0, 0.7, 0.3;  // interval 0 has no arrivals at all
  expectGradientMatches(s, rates, exactStaticGradient(s, rates), 0);
}

TEST(RealizedCostSampler, SubsampledSensorsKeepTheGradientUnbiased) {
  const Scenario s = staticScalar(3);
  MatrixXd rates(3, 2);
  rates << 0.2, 0.0, 1.0, 0.5, 0.0, 1.5;
  expectGradientMatches(s, rates, exactStaticGradient(s, rates), 1);
}

Scenario movingScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 2;
  spec.sensor_count = 2;
  spec.intervals = 3;
  spec.horizon_s = 1.5;
  spec.budget = 3.0;
  spec.seed = 5;
  Scenario s = generateRandomScenario(spec);
  s.cost.W = 0.5 * MatrixXd::Identity(2, 2);  // also a running cost
  return s;
}

// With dynamics there is no closed form: the add-one-point estimate of one entry against a
// central finite difference of common-random-number Monte Carlo (2 x 4000 episodes a batch,
// h = 10% of the rate, whose O(h^2) bias is far below the batches' spread), on 20 batches: a
// paired t-test of the batch differences at two-sided level 1e-3.
TEST(RealizedCostSampler, GradientAgreesWithFiniteDifferenceOfCommonRandomNumbers) {
  const Scenario s = movingScenario();
  MatrixXd rates(3, 2);
  rates << 1.0, 0.5, 1.2, 0.8, 0.4, 1.0;
  PlanRequest request;
  const RealizedCostSampler sampler(s, request, 2);
  const double h = 0.1;
  for (const auto& [k, j] : {std::pair{1, 0}, std::pair{2, 1}}) {
    std::vector<double> differences;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      MatrixXd up = rates, down = rates;
      up(k, j) += h * rates(k, j);
      down(k, j) -= h * rates(k, j);
      const double fd = (meanOf(sampler.episodeCosts(up, seed, 0, 4000)) -
                         meanOf(sampler.episodeCosts(down, seed, 0, 4000))) /
                        (2.0 * h * rates(k, j));
      const double g = sampler.gradient(rates, seed + 1000, 400, {0, 1}, 0).gradient(k, j);
      differences.push_back(g - fd);
    }
    EXPECT_NEAR(meanOf(differences), 0.0, studentTQuantile(0.9995, 19.0) * stdErrorOf(differences))
        << "entry (" << k << ", " << j << ")";
  }
}

Scenario smallPlanningScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 5;
  spec.intervals = 6;
  spec.horizon_s = 1.5;
  spec.budget = 4.0;
  spec.seed = 21;
  return generateRandomScenario(spec);
}

PlanRequest mcRequest() {
  PlanRequest request;
  request.surrogate = PlanSurrogate::MonteCarlo;
  request.max_seconds = 20.0;
  request.max_iterations = 15;
  request.realized.screening_episodes = 600;
  request.realized.gradient_episodes = 32;
  request.realized.acceptance_episodes = 3000;
  request.realized.report_episodes = 3000;
  return request;
}

// The returned schedule is never significantly worse than the best of info, cov and uniform:
// all four scored by the independent evaluator (evaluateSchedule, other generator and seed) on
// the same 20000 episodes, a paired one-sided t-test at level 1e-3.
TEST(McPlanner, NeverWorseThanTheBestSurrogatePlanOnAPairedTest) {
  const Scenario s = smallPlanningScenario();
  const PlanResult mc = planSchedule(s, mcRequest());
  EXPECT_TRUE(mc.status == PlanStatus::Improved || mc.status == PlanStatus::KeptStart)
      << wordOf(mc.status);
  EXPECT_TRUE(checkFeasibility(mc.schedule, s, 1e-9).feasible);
  EXPECT_GT(mc.objective_half_width, 0.0);
  EXPECT_GT(mc.episodes, 0);
  EXPECT_LE(mc.bracket.info, mc.bracket.cov);
  MonteCarloOptions eval;
  eval.runs = 20000;
  eval.seed = 777;
  eval.simulate_plant = false;
  const std::vector<double> mine = evaluateSchedule(s, mc.schedule, eval).episode_costs;
  for (PlanSurrogate other :
       {PlanSurrogate::Information, PlanSurrogate::Covariance, PlanSurrogate::Uniform}) {
    PlanRequest request;
    request.surrogate = other;
    const std::vector<double> theirs =
        evaluateSchedule(s, planSchedule(s, request).schedule, eval).episode_costs;
    std::vector<double> d;
    for (std::size_t e = 0; e < mine.size(); ++e) d.push_back(mine[e] - theirs[e]);
    EXPECT_LT(meanOf(d), 3.09 * stdErrorOf(d)) << "mc against " << describe(other);
  }
  // Its own score agrees with the independent evaluator (two-sided, level 1e-5).
  const double independent = meanOf(mine);
  EXPECT_NEAR(mc.objective, independent,
              4.42 * std::hypot(mc.objective_half_width / 1.96, stdErrorOf(mine)));
}

TEST(McPlanner, SameResultForAnyThreadCount) {
  const Scenario s = smallPlanningScenario();
  PlanRequest one = mcRequest();
  one.max_iterations = 4;
  one.max_seconds = 1e6;  // no time-dependent sizing
  one.realized.threads = 1;
  PlanRequest two = one;
  two.realized.threads = 2;
  const PlanResult a = planSchedule(s, one);
  const PlanResult b = planSchedule(s, two);
  EXPECT_EQ(a.schedule.rates(), b.schedule.rates());
  EXPECT_EQ(a.objective, b.objective);
  EXPECT_EQ(a.episodes, b.episodes);
}

TEST(McPlanner, BadOptionsAreInputErrors) {
  const Scenario s = smallPlanningScenario();
  const auto refused = [&](const std::function<void(RealizedCostOptions&)>& spoil) {
    PlanRequest request = mcRequest();
    spoil(request.realized);
    EXPECT_THROW((void)planSchedule(s, request), InputError);
  };
  refused([](RealizedCostOptions& o) { o.screening_episodes = 1; });
  refused([](RealizedCostOptions& o) { o.gradient_episodes = 0; });
  refused([](RealizedCostOptions& o) { o.gradient_sensors = -1; });
  refused([](RealizedCostOptions& o) { o.acceptance_episodes = 1; });
  refused([](RealizedCostOptions& o) { o.report_episodes = 0; });
  refused([](RealizedCostOptions& o) { o.threads = -2; });
  refused([](RealizedCostOptions& o) { o.max_episodes = 100; });
  PlanRequest request = mcRequest();
  request.max_seconds = 0.0;
  EXPECT_THROW((void)planSchedule(s, request), InputError);
}

TEST(McPlanner, DescribedAsMcWithTheInformationBracket) {
  EXPECT_EQ(describe(PlanSurrogate::MonteCarlo), "mc");
  EXPECT_EQ(formOf(PlanSurrogate::MonteCarlo), SurrogateForm::Information);
}

}  // namespace
}  // namespace sensornet
