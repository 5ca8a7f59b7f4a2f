// Per-sensor energy budgets ∫_0^T λ_j dt <= E_j: the schedule-level projection against an
// independent algorithm (Dykstra's alternating projections), and every planner against the
// budget: the plan meets it, binds it where the unconstrained plan overspends, and on a
// drift-free plant reaches the optimum of an independent convex solve with the budget as a cap.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <vector>

#include "sensornet/core/random.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/planning/mc_planner.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/planning/rate_polytope.hpp"
#include "unit/planning/drift_free.hpp"

namespace sensornet {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kInf = std::numeric_limits<double>::infinity();

// argmin ||x - y|| over {x >= 0, h Σ x <= e}: max(0, y - μ) with μ >= 0 found by bisection.
VectorXd projectOntoBudget(const VectorXd& y, double h, double e) {
  const auto used = [&](double mu) { return h * (y.array() - mu).cwiseMax(0.0).sum(); };
  if (!(e < kInf) || used(0.0) <= e) return y.cwiseMax(0.0);
  double low = 0.0;
  double high = y.maxCoeff();
  for (int i = 0; i < 200; ++i) {
    const double middle = 0.5 * (low + high);
    (used(middle) > e ? low : high) = middle;
  }
  return (y.array() - high).cwiseMax(0.0).matrix();
}

// Dykstra's method between A = the intervals' polytopes (row by row) and B = the budgets
// (column by column): its iterates converge to the projection onto A ∩ B.
MatrixXd dykstra(const RatePolytope& polytope, const MatrixXd& y, double h,
                 const VectorXd& energy) {
  MatrixXd x = y;
  MatrixXd p = MatrixXd::Zero(y.rows(), y.cols());
  MatrixXd q = p;
  for (int it = 0; it < 4000; ++it) {
    MatrixXd a = x + p;
    MatrixXd pa(a.rows(), a.cols());
    for (Eigen::Index k = 0; k < a.rows(); ++k) {
      pa.row(k) = polytope.project(a.row(k).transpose()).transpose();
    }
    p = a - pa;
    const MatrixXd bq = pa + q;
    for (Eigen::Index j = 0; j < bq.cols(); ++j) {
      x.col(j) = projectOntoBudget(bq.col(j), h, energy(j));
    }
    q = bq - x;
  }
  return x;
}

bool admissible(const RatePolytope& polytope, const MatrixXd& x, double h, const VectorXd& energy) {
  for (Eigen::Index k = 0; k < x.rows(); ++k) {
    if (!polytope.contains(x.row(k).transpose(), 1e-12)) return false;
  }
  for (Eigen::Index j = 0; j < x.cols(); ++j) {
    if (h * x.col(j).sum() > energy(j) * (1.0 + 1e-12)) return false;
  }
  return true;
}

TEST(RatePolytope, ScheduleProjectionUnderEnergyBudgetsMatchesDykstra) {
  ResourceConstraints constraints;
  constraints.C = (MatrixXd(2, 4) << 1, 1, 0, 1, 0, 1, 1, 2).finished();
  constraints.b = VectorXd::Constant(2, 3.0);
  const double h = 0.3;
  const VectorXd energy = (VectorXd(4) << 0.6, kInf, 1.0, 0.3).finished();
  for (const std::vector<int>& excluded : {std::vector<int>{}, std::vector<int>{2}}) {
    const RatePolytope polytope(constraints, excluded);
    Rng rng(23);
    for (int trial = 0; trial < 12; ++trial) {
      MatrixXd y(5, 4);
      for (Eigen::Index k = 0; k < y.rows(); ++k) {
        for (Eigen::Index j = 0; j < y.cols(); ++j) y(k, j) = 1.0 + 2.0 * rng.normal();
      }
      const MatrixXd p = polytope.projectSchedule(y, h, energy);
      ASSERT_TRUE(admissible(polytope, p, h, energy)) << p;
      if (!excluded.empty()) {
        EXPECT_TRUE(p.col(2).isZero(0.0));
      }
      const MatrixXd expected = dykstra(polytope, y, h, energy);
      EXPECT_LE((p - expected).cwiseAbs().maxCoeff(), 1e-7) << "trial " << trial << "\n"
                                                            << p << "\n\n"
                                                            << expected;
    }
  }
}

TEST(RatePolytope, AnExhaustedBudgetLeavesTheSensorNothingAndTheUniformRatesMeetTheBudgets) {
  ResourceConstraints constraints;
  constraints.C = MatrixXd::Ones(1, 3);
  constraints.b = VectorXd::Constant(1, 6.0);
  const RatePolytope polytope(constraints);
  const VectorXd energy = (VectorXd(3) << 0.0, 1.0, kInf).finished();
  const MatrixXd p = polytope.projectSchedule(MatrixXd::Constant(4, 3, 5.0), 0.5, energy);
  EXPECT_TRUE(p.col(0).isZero(0.0));
  EXPECT_NEAR(0.5 * p.col(1).sum(), 1.0, 1e-12);
  // 4 intervals of 0.5 s: 2 s; the uniform rate 2 Hz, sensor 1 capped at 1 / 2 s.
  const MatrixXd u = polytope.uniformSchedule(4, 0.5, energy);
  EXPECT_TRUE(u.col(0).isZero(0.0));
  EXPECT_TRUE(u.col(1).isConstant(0.5));
  EXPECT_TRUE(u.col(2).isConstant(2.0));
}

VectorXd energyUsed(const RateSchedule& schedule) {
  return schedule.expectedCounts(0.0, schedule.horizon());
}

// The drift-free plant with a budget of half what the unconstrained plan spends on its most
// used sensor, none on sensor 0, and an ample one (twice the whole budget's) on the others.
Scenario withBindingBudget(Scenario s, int& binding) {
  const VectorXd used = energyUsed(planSchedule(s, {}).schedule);
  used.maxCoeff(&binding);
  s.constraints.energy =
      VectorXd::Constant(s.sensorCount(), 2.0 * s.constraints.b(0) * s.horizon_s);
  s.constraints.energy(0) = kInf;
  s.constraints.energy(binding) = 0.5 * used(binding);
  if (binding == 0) s.constraints.energy(0) = 0.5 * used(0);
  validateScenario(s, "test");
  return s;
}

TEST(EnergyBudget, BothOptimizersReachTheCappedConvexOptimumWithTheBudgetBinding) {
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    const Scenario free = testing::driftFreeScenario(seed, 5);
    const double unconstrained = planSchedule(free, {}).objective;
    int binding = -1;
    const Scenario s = withBindingBudget(free, binding);
    const double optimum = testing::convexInformationOptimum(s);
    EXPECT_GT(optimum, unconstrained * (1.0 + 1e-6)) << "the budget must cost something";
    for (const PlanMethod method : {PlanMethod::ProjectedGradient, PlanMethod::Ipopt}) {
      PlanRequest request;
      request.method = method;
      const PlanResult plan = planSchedule(s, request);
      const std::string what = "seed " + std::to_string(seed) + " " + std::string(wordOf(method));
      const Feasibility f = checkFeasibility(plan.schedule, s, 1e-9);
      EXPECT_TRUE(f.feasible) << what << ": " << f.reason;
      EXPECT_TRUE(plan.status == PlanStatus::Optimal || plan.status == PlanStatus::Acceptable)
          << what << ": " << wordOf(plan.status);
      EXPECT_NEAR(plan.objective, optimum, 1e-6 * optimum) << what;
      const VectorXd used = energyUsed(plan.schedule);
      EXPECT_NEAR(used(binding), s.constraints.energy(binding),
                  1e-6 * s.constraints.energy(binding))
          << what << ": the budget of sensor " << binding << " binds";
    }
  }
}

Scenario budgetedRandomScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 6;
  spec.intervals = 8;
  spec.horizon_s = 1.5;
  spec.budget = 6.0;
  spec.seed = 5;
  Scenario s = generateRandomScenario(spec);
  const VectorXd used = energyUsed(planSchedule(s, {}).schedule);
  s.constraints.energy = 0.6 * used.cwiseMax(0.5);  // every sensor below what it would spend
  s.constraints.energy(5) = kInf;
  validateScenario(s, "test");
  return s;
}

TEST(EnergyBudget, EverySurrogatePlanAndTheUniformBaselineMeetIt) {
  const Scenario s = budgetedRandomScenario();
  for (const PlanSurrogate surrogate :
       {PlanSurrogate::Information, PlanSurrogate::Covariance, PlanSurrogate::Uniform}) {
    PlanRequest request;
    request.surrogate = surrogate;
    const PlanResult plan = planSchedule(s, request);
    const Feasibility f = checkFeasibility(plan.schedule, s, 1e-9);
    EXPECT_TRUE(f.feasible) << describe(surrogate) << ": " << f.reason;
    if (surrogate == PlanSurrogate::Uniform) {
      // The largest equal rate under 1'λ <= b, each sensor capped at E_j / T.
      const double rate = s.constraints.b(0) / s.sensorCount();
      for (int j = 0; j < s.sensorCount(); ++j) {
        EXPECT_DOUBLE_EQ(plan.schedule.rate(3, j),
                         std::min(rate, s.constraints.energy(j) / s.horizon_s));
      }
      EXPECT_TRUE(plan.schedule.rates().isApprox(uniformSchedule(s).rates(), 0.0));
      continue;
    }
    EXPECT_EQ(plan.status, PlanStatus::Optimal) << describe(surrogate);
    EXPECT_LT(plan.kkt_residual, 1e-6) << describe(surrogate);
    const VectorXd used = energyUsed(plan.schedule);
    int bound = 0;
    for (int j = 0; j < 5; ++j) {
      bound += used(j) >= s.constraints.energy(j) * (1.0 - 1e-6) ? 1 : 0;
    }
    EXPECT_GE(bound, 1) << describe(surrogate) << ": some budget below the free plan's use binds";
  }
}

// Re-planned from 0.7 s (inside interval 3) warm-started at the schedule in force: what that
// schedule spent before 0.7 s counts, so both the schedule as written and the rates in force
// over time (the old ones before 0.7 s, the new ones after) meet every budget.
TEST(EnergyBudget, AReplanSpendsOnlyWhatTheScheduleInForceLeft) {
  const Scenario s = budgetedRandomScenario();
  const RateSchedule in_force = uniformSchedule(s);
  PlanRequest request;
  request.start_time = 0.7;
  request.start_covariance = 0.3 * s.plant.P0;
  request.warm_start = in_force;
  for (const PlanMethod method : {PlanMethod::ProjectedGradient, PlanMethod::Ipopt}) {
    request.method = method;
    const PlanResult plan = planSchedule(s, request);
    const std::string what(wordOf(method));
    EXPECT_TRUE(checkFeasibility(plan.schedule, s, 1e-9).feasible) << what;
    const VectorXd over_time =
        in_force.expectedCounts(0.0, 0.7) + plan.schedule.expectedCounts(0.7, s.horizon_s);
    for (int j = 0; j < 5; ++j) {
      EXPECT_LE(over_time(j), s.constraints.energy(j) * (1.0 + 1e-9)) << what << " sensor " << j;
    }
    EXPECT_TRUE(plan.status == PlanStatus::Optimal || plan.status == PlanStatus::Acceptable)
        << what << ": " << wordOf(plan.status);
  }
}

TEST(EnergyBudget, TheMonteCarloPlannerMeetsIt) {
  const Scenario s = budgetedRandomScenario();
  PlanRequest request;
  request.surrogate = PlanSurrogate::MonteCarlo;
  request.max_seconds = 20.0;
  request.realized.threads = 2;
  request.realized.screening_episodes = 200;
  request.realized.acceptance_episodes = 500;
  request.realized.report_episodes = 500;
  request.max_iterations = 10;
  const PlanResult plan = planSchedule(s, request);
  const Feasibility f = checkFeasibility(plan.schedule, s, 1e-9);
  EXPECT_TRUE(f.feasible) << f.reason;
}

}  // namespace
}  // namespace sensornet
