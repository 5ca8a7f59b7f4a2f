#pragma once
// Independent references for the surrogates of the first paper, written from its equations and
// sharing nothing with src/core: the exact Hamiltonian (linear-fractional) solution of the
// information-form Riccati flow, eq. (11) with constant rates on an interval, and a brute-force
// fixed-step RK4 of the covariance form, eq. (15), written sensor by sensor. Used by the
// surrogate tests and by the Corollary 1 sweep of the first paper's Fig. 2.

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet::reference {

using Eigen::MatrixXd;

inline double frobenius(const MatrixXd& a, const MatrixXd& b) { return a.cwiseProduct(b).sum(); }

// U = Σ_j λ_j H_j' R_j^{-1} H_j on interval k.
inline MatrixXd informationRate(const Scenario& s, const RateSchedule& schedule, int k) {
  MatrixXd u = MatrixXd::Zero(s.stateDim(), s.stateDim());
  for (int j = 0; j < s.sensorCount(); ++j) {
    const auto& sensor = s.sensors[static_cast<std::size_t>(j)];
    u += schedule.rate(k, j) * sensor.H.transpose() * sensor.R.inverse() * sensor.H;
  }
  return u;
}

// Exact solution of Ṗ = A P + P A' + Q - P U P over a time h: with P = X Z^{-1} and
// d/dt [X; Z] = [[A, Q], [U, -A']] [X; Z], P(h) = (Φ11 P + Φ12)(Φ21 P + Φ22)^{-1}.
inline MatrixXd exactRiccatiStep(const MatrixXd& A, const MatrixXd& Q, const MatrixXd& U,
                          const MatrixXd& P, double h) {
  const Eigen::Index n = A.rows();
  MatrixXd hamiltonian(2 * n, 2 * n);
  hamiltonian << A, Q, U, -A.transpose();
  const MatrixXd phi = (h * hamiltonian).exp();
  const MatrixXd x = phi.topLeftCorner(n, n) * P + phi.topRightCorner(n, n);
  const MatrixXd z = phi.bottomLeftCorner(n, n) * P + phi.bottomRightCorner(n, n);
  const MatrixXd p = z.transpose().partialPivLu().solve(x.transpose()).transpose();
  return 0.5 * (p + p.transpose());
}

// Ṗ = A P + P A' + Q - Σ_j λ_j g_j(P), written from the paper sensor by sensor, and the
// running-cost rate <W, P>, by classical RK4 with a fixed step that divides every interval.
struct Rk4Result {
  std::vector<MatrixXd> boundaries;
  double running_cost = 0.0;
};
inline Rk4Result covarianceFormByRk4(const Scenario& s, const RateSchedule& schedule,
                              int steps_per_interval) {
  const MatrixXd& A = s.plant.A;
  auto drift = [&](const MatrixXd& P, int k) {
    MatrixXd dp = A * P + P * A.transpose() + s.plant.Q;
    for (int j = 0; j < s.sensorCount(); ++j) {
      const auto& sensor = s.sensors[static_cast<std::size_t>(j)];
      const MatrixXd innovation = sensor.H * P * sensor.H.transpose() + sensor.R;
      dp -= schedule.rate(k, j) * P * sensor.H.transpose() * innovation.inverse() * sensor.H * P;
    }
    return dp;
  };
  Rk4Result result;
  MatrixXd P = s.plant.P0;
  result.boundaries.push_back(P);
  const double h = schedule.intervalLength() / steps_per_interval;
  for (int k = 0; k < schedule.intervals(); ++k) {
    for (int step = 0; step < steps_per_interval; ++step) {
      const MatrixXd k1 = drift(P, k);
      const MatrixXd k2 = drift(P + 0.5 * h * k1, k);
      const MatrixXd k3 = drift(P + 0.5 * h * k2, k);
      const MatrixXd k4 = drift(P + h * k3, k);
      // The cost rate <W, P> is linear in P, so RK4 on the augmented state gives
      // h/6 (c(P) + 2 c(P2) + 2 c(P3) + c(P4)) with the stage states P2, P3, P4.
      result.running_cost +=
          h / 6.0 *
          (frobenius(s.cost.W, P) + 2.0 * frobenius(s.cost.W, P + 0.5 * h * k1) +
           2.0 * frobenius(s.cost.W, P + 0.5 * h * k2) + frobenius(s.cost.W, P + h * k3));
      P += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    result.boundaries.push_back(P);
  }
  return result;
}

// The information-form covariances P_info = Ys^{-1} at every interval boundary, from P0 (the
// exact solution, interval by interval).
inline std::vector<MatrixXd> informationFormExact(const Scenario& s, const RateSchedule& schedule) {
  std::vector<MatrixXd> boundaries{s.plant.P0};
  for (int k = 0; k < schedule.intervals(); ++k) {
    boundaries.push_back(exactRiccatiStep(s.plant.A, s.plant.Q, informationRate(s, schedule, k),
                                          boundaries.back(), schedule.intervalLength()));
  }
  return boundaries;
}

}  // namespace sensornet::reference
