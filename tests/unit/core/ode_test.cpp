#include "sensornet/core/ode.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace sensornet {
namespace {

// y'' = -ω² y as a first-order system; y(t) = cos(ω t), y'(t) = -ω sin(ω t).
void oscillator(double, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
  constexpr double omega = 3.0;
  dydt(0) = y(1);
  dydt(1) = -omega * omega * y(0);
}

// y' = -2 t y, y(0) = 1: y(t) = exp(-t²). Non-autonomous, so the stage times c_i matter too.
void gaussian(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
  dydt(0) = -2.0 * t * y(0);
}

double gaussianErrorWithFixedStep(double step) {
  OdeOptions options;
  options.relative_tolerance = 1.0;  // every step passes: the step is fixed by max_step
  options.absolute_tolerance = 1.0;
  options.initial_step = step;
  options.max_step = step;
  const OdeSolution s =
      integrateDormandPrince(gaussian, 0.0, 2.0, Eigen::VectorXd::Ones(1), options);
  EXPECT_EQ(s.status, OdeStatus::Success);
  EXPECT_EQ(s.rejected_steps, 0);
  return std::abs(s.y(0) - std::exp(-4.0));
}

TEST(DormandPrince, ConvergesAtFifthOrderWithAFixedStep) {
  // Global error C h^5: halving the step divides it by 32. A wrong tableau entry drops the
  // order (a ratio of 16 or less) long before it shows as a visibly wrong answer.
  // The observed orders here are 5.2 and 5.04, approaching 5 from above.
  const double coarse = gaussianErrorWithFixedStep(0.025);
  const double fine = gaussianErrorWithFixedStep(0.0125);
  const double finer = gaussianErrorWithFixedStep(0.00625);
  EXPECT_GT(finer, 0.0);
  EXPECT_NEAR(std::log2(coarse / fine), 5.0, 0.3) << coarse << " " << fine;
  EXPECT_NEAR(std::log2(fine / finer), 5.0, 0.3) << fine << " " << finer;
}

TEST(DormandPrince, MeetsTheToleranceOnAnOscillatorOverManyPeriods) {
  const double t1 = 10.0;  // about five periods
  double previous_error = 1.0;
  for (double tol : {1e-6, 1e-8, 1e-10}) {
    OdeOptions options;
    options.relative_tolerance = tol;
    options.absolute_tolerance = tol;
    const OdeSolution s =
        integrateDormandPrince(oscillator, 0.0, t1, Eigen::Vector2d(1.0, 0.0), options);
    ASSERT_EQ(s.status, OdeStatus::Success);
    const double error =
        std::hypot(s.y(0) - std::cos(3.0 * t1), (s.y(1) + 3.0 * std::sin(3.0 * t1)) / 3.0);
    // Local control gives a global error within a modest multiple of the tolerance.
    EXPECT_LT(error, 50.0 * tol) << "tol " << tol;
    EXPECT_LT(error, previous_error);
    previous_error = error;
  }
}

TEST(DormandPrince, EndsExactlyAtTheEndTime) {
  OdeOptions options;
  options.relative_tolerance = 1e-7;
  const double t1 = 0.7 + 1e-13;
  const OdeSolution s =
      integrateDormandPrince(oscillator, 0.1, t1, Eigen::Vector2d(1.0, 0.0), options);
  EXPECT_EQ(s.status, OdeStatus::Success);
  EXPECT_EQ(s.t, t1);
  EXPECT_GT(s.next_step, 0.0);
}

TEST(DormandPrince, AnEmptyIntervalReturnsTheStartStateWithoutEvaluating) {
  int calls = 0;
  const OdeRightHandSide f = [&calls](double, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    ++calls;
    dydt = y;
  };
  const OdeSolution s = integrateDormandPrince(f, 1.0, 1.0, Eigen::Vector2d(2.0, 3.0), {});
  EXPECT_EQ(s.status, OdeStatus::Success);
  EXPECT_EQ(s.y, Eigen::Vector2d(2.0, 3.0));
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(s.accepted_steps, 0);
}

TEST(DormandPrince, ReusesTheLastStageOfEachStep) {
  int calls = 0;
  const OdeRightHandSide f = [&calls](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    ++calls;
    oscillator(t, y, dydt);
  };
  OdeOptions options;
  options.relative_tolerance = 1e-9;
  options.initial_step = 0.5;  // too large: forces some rejections
  const OdeSolution s = integrateDormandPrince(f, 0.0, 4.0, Eigen::Vector2d(1.0, 0.0), options);
  ASSERT_EQ(s.status, OdeStatus::Success);
  EXPECT_GT(s.rejected_steps, 0);
  // One evaluation at the start, then six new stages per attempted step (FSAL).
  EXPECT_EQ(calls, 1 + 6 * (s.accepted_steps + s.rejected_steps));
  EXPECT_EQ(s.rhs_evaluations, calls);
}

TEST(DormandPrince, ReportsTooManyStepsInsteadOfThrowing) {
  OdeOptions options;
  options.relative_tolerance = 1e-12;
  options.max_steps = 5;
  const OdeSolution s =
      integrateDormandPrince(oscillator, 0.0, 100.0, Eigen::Vector2d(1.0, 0.0), options);
  EXPECT_EQ(s.status, OdeStatus::TooManySteps);
  EXPECT_LT(s.t, 100.0);
  EXPECT_EQ(s.accepted_steps + s.rejected_steps, 5);
  EXPECT_EQ(describe(s.status), "too many steps");
}

TEST(DormandPrince, RetreatsWhenAStageLeavesTheDomain) {
  // y' = -sqrt(y), y(0) = 1: y(t) = (1 - t/2)². A first step of 10 makes the second stage
  // negative, so f returns NaN there; the integrator must shrink the step, not give up.
  const OdeRightHandSide f = [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) {
    dydt(0) = -std::sqrt(y(0));
  };
  OdeOptions options;
  options.relative_tolerance = 1e-10;
  options.initial_step = 10.0;
  const OdeSolution s = integrateDormandPrince(f, 0.0, 1.0, Eigen::VectorXd::Ones(1), options);
  ASSERT_EQ(s.status, OdeStatus::Success);
  EXPECT_GT(s.rejected_steps, 0);
  EXPECT_NEAR(s.y(0), 0.25, 1e-9);
}

TEST(DormandPrince, UsesTheSuppliedErrorNorm) {
  int norm_calls = 0;
  OdeOptions options;
  options.initial_step = 1e-3;
  // An error norm that never objects: the step grows by the controller's limit of 10 each
  // time, so [0, 1] takes 1e-3, 1e-2, 1e-1 and then the rest in one step.
  options.error_norm = [&norm_calls](const Eigen::VectorXd&, const Eigen::VectorXd&,
                                     const Eigen::VectorXd&) {
    ++norm_calls;
    return 0.0;
  };
  const OdeSolution s =
      integrateDormandPrince(oscillator, 0.0, 1.0, Eigen::Vector2d(1.0, 0.0), options);
  EXPECT_EQ(s.status, OdeStatus::Success);
  EXPECT_EQ(s.accepted_steps, 4);
  EXPECT_EQ(norm_calls, 4);
}

}  // namespace
}  // namespace sensornet
