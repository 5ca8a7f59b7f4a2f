#pragma once
// Adaptive integration of an ordinary differential equation y' = f(t, y) over [t0, t1] with the
// Dormand-Prince 5(4) embedded Runge-Kutta pair: fifth-order solution, fourth-order error
// estimate, first-same-as-last stages (six right-hand-side evaluations per accepted step) and a
// PI step-size controller (Hairer, Nørsett & Wanner, Solving ODEs I, sections II.4 and II.5).
//
// The error norm is replaceable, so that a caller whose state is a matrix can measure the local
// error in the way that suits the matrix (relative to the matrix itself, for example) instead of
// entry by entry.
//
//   OdeOptions options;
//   options.relative_tolerance = 1e-9;
//   const OdeSolution s = integrateDormandPrince(
//       [](double, const Eigen::VectorXd& y, Eigen::VectorXd& dydt) { dydt = -y; },
//       0.0, 1.0, Eigen::VectorXd::Ones(3), options);
//   // s.status == OdeStatus::Success, s.y ≈ exp(-1) (1, 1, 1)

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string_view>

namespace sensornet {

// Writes f(t, y) into dydt, which arrives with the size of y (so no allocation is needed).
using OdeRightHandSide =
    std::function<void(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dydt)>;

// The size of a local error estimate in units of the tolerance: a step is accepted when the
// result is <= 1. y_old is the state at the start of the step, y_new the proposed state.
using OdeErrorNorm = std::function<double(
    const Eigen::VectorXd& y_old, const Eigen::VectorXd& y_new, const Eigen::VectorXd& error)>;

struct OdeOptions {
  double relative_tolerance = 1e-9;
  double absolute_tolerance = 1e-12;
  double initial_step = 0.0;  // 0: chosen automatically from f at t0
  double max_step = std::numeric_limits<double>::infinity();
  int max_steps = 100000;  // accepted plus rejected steps before giving up
  // Empty: the root mean square over components i of
  // error_i / (atol + rtol max(|y_old_i|, |y_new_i|)).
  OdeErrorNorm error_norm;
};

enum class OdeStatus { Success, TooManySteps, StepSizeTooSmall };

struct OdeSolution {
  Eigen::VectorXd y;  // the state at t1 (or where integration stopped)
  double t = 0.0;     // t1 on success
  OdeStatus status = OdeStatus::Success;
  int accepted_steps = 0;
  int rejected_steps = 0;
  int rhs_evaluations = 0;
  double next_step = 0.0;  // the controller's proposal for a following step, for restarts
};

// Integrates from (t0, y0) to t1 >= t0, ending exactly at t1. Never throws for a hard problem:
// status says why it stopped early.
[[nodiscard]] OdeSolution integrateDormandPrince(const OdeRightHandSide& f, double t0, double t1,
                                                 Eigen::VectorXd y0, const OdeOptions& options);

[[nodiscard]] std::string_view describe(OdeStatus status);

}  // namespace sensornet
