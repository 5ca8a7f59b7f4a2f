#include "sensornet/core/ode.hpp"

#include <algorithm>
#include <cmath>

namespace sensornet {
namespace {

// Dormand-Prince 5(4) tableau (Dormand & Prince 1980). Row 7 equals the fifth-order weights, so
// the last stage of a step is the first stage of the next (FSAL).
constexpr double c2 = 1.0 / 5.0, c3 = 3.0 / 10.0, c4 = 4.0 / 5.0, c5 = 8.0 / 9.0;
constexpr double a21 = 1.0 / 5.0;
constexpr double a31 = 3.0 / 40.0, a32 = 9.0 / 40.0;
constexpr double a41 = 44.0 / 45.0, a42 = -56.0 / 15.0, a43 = 32.0 / 9.0;
constexpr double a51 = 19372.0 / 6561.0, a52 = -25360.0 / 2187.0, a53 = 64448.0 / 6561.0,
                 a54 = -212.0 / 729.0;
constexpr double a61 = 9017.0 / 3168.0, a62 = -355.0 / 33.0, a63 = 46732.0 / 5247.0,
                 a64 = 49.0 / 176.0, a65 = -5103.0 / 18656.0;
constexpr double a71 = 35.0 / 384.0, a73 = 500.0 / 1113.0, a74 = 125.0 / 192.0,
                 a75 = -2187.0 / 6784.0, a76 = 11.0 / 84.0;
// Fifth-order minus fourth-order weights: the local error estimate is h Σ e_i k_i.
constexpr double e1 = 71.0 / 57600.0, e3 = -71.0 / 16695.0, e4 = 71.0 / 1920.0,
                 e5 = -17253.0 / 339200.0, e6 = 22.0 / 525.0, e7 = -1.0 / 40.0;

// Step-size controller: h_new = h err^-alpha err_prev^beta / safety, the change limited to
// [1/5, 10]; alpha = 1/5 - 0.75 beta is the PI choice for a fourth-order error estimate.
constexpr double kSafety = 0.9;
constexpr double kBeta = 0.04;
constexpr double kAlpha = 0.2 - 0.75 * kBeta;
constexpr double kMinShrink = 0.2;
constexpr double kMaxGrowth = 10.0;

OdeErrorNorm componentwiseNorm(double rtol, double atol) {
  return [rtol, atol](const Eigen::VectorXd& y_old, const Eigen::VectorXd& y_new,
                      const Eigen::VectorXd& error) {
    if (error.size() == 0) return 0.0;
    const Eigen::ArrayXd scale = atol + rtol * y_old.array().abs().max(y_new.array().abs());
    return std::sqrt((error.array() / scale).square().mean());
  };
}

// The starting step of Hairer & Wanner's DOPRI5 code: a step on which an explicit Euler step
// would change y by about 1% of its size, refined by an estimate of the second derivative.
double initialStep(const OdeRightHandSide& f, const OdeErrorNorm& norm, double t,
                   const Eigen::VectorXd& y, const Eigen::VectorXd& dydt, double span,
                   double max_step, int& evaluations) {
  const double d0 = norm(y, y, y);
  const double d1 = norm(y, y, dydt);
  double h0 = (d0 < 1e-10 || d1 < 1e-10) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min({h0, max_step, span});
  const Eigen::VectorXd y1 = y + h0 * dydt;
  Eigen::VectorXd dydt1(y.size());
  f(t + h0, y1, dydt1);
  ++evaluations;
  const double d2 = norm(y, y1, dydt1 - dydt) / h0;
  const double d = std::max(d1, d2);
  const double h1 =
      (d <= 1e-15 || !std::isfinite(d)) ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / d, 0.2);
  return std::min({100.0 * h0, h1, max_step});
}

}  // namespace

OdeSolution integrateDormandPrince(const OdeRightHandSide& f, double t0, double t1,
                                   Eigen::VectorXd y0, const OdeOptions& options) {
  OdeSolution solution;
  solution.y = std::move(y0);
  solution.t = t0;
  solution.next_step = options.initial_step;
  if (!(t1 > t0)) return solution;

  const OdeErrorNorm norm = options.error_norm ? options.error_norm
                                               : componentwiseNorm(options.relative_tolerance,
                                                                   options.absolute_tolerance);
  const Eigen::Index m = solution.y.size();
  Eigen::VectorXd& y = solution.y;
  Eigen::VectorXd k1(m), k2(m), k3(m), k4(m), k5(m), k6(m), k7(m);
  Eigen::VectorXd stage(m), y_new(m), error(m);
  double& t = solution.t;

  f(t, y, k1);
  solution.rhs_evaluations = 1;
  double h = options.initial_step > 0.0 ? std::min(options.initial_step, options.max_step)
                                        : initialStep(f, norm, t, y, k1, t1 - t0, options.max_step,
                                                      solution.rhs_evaluations);
  double previous_error = 1e-4;
  bool previous_rejected = false;

  while (true) {
    if (solution.accepted_steps + solution.rejected_steps >= options.max_steps) {
      solution.status = OdeStatus::TooManySteps;
      solution.next_step = h;
      return solution;
    }
    // The last step lands on t1 exactly; a step that would stop just short of t1 is stretched
    // rather than followed by a sliver.
    const double proposal = h;
    const bool last = t + 1.0001 * h >= t1;
    if (last) {
      h = t1 - t;
    } else if (h <= 16.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(t), 1.0)) {
      solution.status = OdeStatus::StepSizeTooSmall;
      solution.next_step = h;
      return solution;
    }

    stage.noalias() = y + (h * a21) * k1;
    f(t + c2 * h, stage, k2);
    stage.noalias() = y + h * (a31 * k1 + a32 * k2);
    f(t + c3 * h, stage, k3);
    stage.noalias() = y + h * (a41 * k1 + a42 * k2 + a43 * k3);
    f(t + c4 * h, stage, k4);
    stage.noalias() = y + h * (a51 * k1 + a52 * k2 + a53 * k3 + a54 * k4);
    f(t + c5 * h, stage, k5);
    stage.noalias() = y + h * (a61 * k1 + a62 * k2 + a63 * k3 + a64 * k4 + a65 * k5);
    f(t + h, stage, k6);
    y_new.noalias() = y + h * (a71 * k1 + a73 * k3 + a74 * k4 + a75 * k5 + a76 * k6);
    f(t + h, y_new, k7);
    solution.rhs_evaluations += 6;
    error.noalias() = h * (e1 * k1 + e3 * k3 + e4 * k4 + e5 * k5 + e6 * k6 + e7 * k7);
    const double err = norm(y, y_new, error);

    if (!std::isfinite(err)) {
      // A stage left the domain of f (or overflowed): retreat sharply.
      ++solution.rejected_steps;
      previous_rejected = true;
      h *= kMinShrink;
      continue;
    }
    const double growth_inverse = std::pow(err, kAlpha);
    if (err <= 1.0) {
      double factor = growth_inverse / std::pow(previous_error, kBeta) / kSafety;
      factor = std::clamp(factor, 1.0 / kMaxGrowth, 1.0 / kMinShrink);
      double h_next = h / factor;
      if (previous_rejected) h_next = std::min(h_next, h);
      previous_error = std::max(err, 1e-4);
      previous_rejected = false;
      y.swap(y_new);
      k1.swap(k7);
      ++solution.accepted_steps;
      if (last) {
        t = t1;
        // A shortened last step says little about the step the solution allows.
        solution.next_step = std::min(std::max(h_next, proposal), options.max_step);
        return solution;
      }
      t += h;
      h = std::min(h_next, options.max_step);
    } else {
      ++solution.rejected_steps;
      previous_rejected = true;
      h /= std::min(1.0 / kMinShrink, growth_inverse / kSafety);
    }
  }
}

std::string_view describe(OdeStatus status) {
  switch (status) {
    case OdeStatus::Success:
      return "success";
    case OdeStatus::TooManySteps:
      return "too many steps";
    case OdeStatus::StepSizeTooSmall:
      return "step size too small";
  }
  return "unknown";
}

}  // namespace sensornet
