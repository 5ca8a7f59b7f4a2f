#pragma once
// A drift-free plant (A = 0, Q = 0, W = 0), where the information-form plan has an independent
// answer: the cost depends on the rates only through their time averages, a convex problem
// over a capped simplex, solved here by projected gradient (planner_test.cpp,
// energy_budget_test.cpp).

#include <Eigen/LU>
#include <cstdint>
#include <limits>

#include "sensornet/core/scenario.hpp"

namespace sensornet::testing {

// A random scenario of the first paper's family (3 states, 6 intervals, T = 1.5 s, 1'λ <= 3)
// made drift-free: A = 0, Q = 0, P0 = 4 I.
inline Scenario driftFreeScenario(std::uint64_t seed, int sensors) {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = sensors;
  spec.intervals = 6;
  spec.horizon_s = 1.5;
  spec.budget = 3.0;
  spec.seed = seed;
  Scenario s = generateRandomScenario(spec);
  s.plant.A.setZero();
  s.plant.Q.setZero();
  s.plant.P0 = 4.0 * Eigen::MatrixXd::Identity(3, 3);
  return s;
}

// With A = 0, Q = 0 and W = 0 the information form is Y(T) = Y0 + T Σ_j ā_j S_j with
// ā_j = Σ_k λ_kj / N, so J = <W_T, Y(T)^-1> depends on the rates only through the averages, and
// the schedules meeting 1'λ_k <= b and the energy budgets T ā_j <= E_j have exactly the averages
// in {ā >= 0, 1'ā <= b, ā_j <= E_j / T} (a constant schedule realizes any of them). The convex
// problem over that set, solved by projected gradient with Armijo backtracking and a bisection
// projection (200 halvings of the multiplier).
inline double convexInformationOptimum(const Scenario& s) {
  const auto increments = s.informationIncrements();
  const Eigen::MatrixXd Y0 = s.plant.P0.inverse();
  const double T = s.horizon_s;
  const double budget = s.constraints.b(0);
  const Eigen::VectorXd cap =
      s.constraints.energy.size() > 0
          ? Eigen::VectorXd(s.constraints.energy / T)
          : Eigen::VectorXd::Constant(s.sensorCount(), std::numeric_limits<double>::infinity());
  const auto information = [&](const Eigen::VectorXd& l) {
    Eigen::MatrixXd Y = Y0;
    for (int j = 0; j < l.size(); ++j) Y += T * l(j) * increments[static_cast<std::size_t>(j)];
    return Y;
  };
  const auto cost = [&](const Eigen::VectorXd& l) {
    return (s.cost.WT * information(l).inverse()).trace();
  };
  const auto gradient = [&](const Eigen::VectorXd& l) {
    const Eigen::MatrixXd P = information(l).inverse();
    const Eigen::MatrixXd PWP = P * s.cost.WT * P;
    Eigen::VectorXd g(l.size());
    for (int j = 0; j < l.size(); ++j) {
      g(j) = -T * PWP.cwiseProduct(increments[static_cast<std::size_t>(j)]).sum();
    }
    return g;
  };
  const auto project = [&](const Eigen::VectorXd& y) {
    const auto clipped = [&](double mu) {
      return Eigen::VectorXd((y.array() - mu).max(0.0).min(cap.array()));
    };
    if (clipped(0.0).sum() <= budget) return clipped(0.0);
    double low = 0.0;
    double high = y.maxCoeff();
    for (int it = 0; it < 200; ++it) {
      const double middle = 0.5 * (low + high);
      (clipped(middle).sum() > budget ? low : high) = middle;
    }
    return clipped(high);
  };
  Eigen::VectorXd l = project(Eigen::VectorXd::Constant(s.sensorCount(), budget / s.sensorCount()));
  double f = cost(l);
  double step = 1.0;
  for (int it = 0; it < 20000; ++it) {
    const Eigen::VectorXd g = gradient(l);
    for (;;) {
      const Eigen::VectorXd trial = project(l - step * g);
      const double ft = cost(trial);
      if (ft <= f + 1e-4 * g.dot(trial - l) || step < 1e-14) {
        l = trial;
        f = ft;
        break;
      }
      step *= 0.5;
    }
    step *= 2.0;
  }
  return f;
}

}  // namespace sensornet::testing
