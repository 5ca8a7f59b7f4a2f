#include "sensornet/core/cdkf.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/scenario.hpp"
#include "support/eigen_near.hpp"

namespace sensornet {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

using testing::relativeError;

MatrixXd gaussianMatrix(Eigen::Index rows, Eigen::Index cols, Rng& rng) {
  MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) m(i, j) = rng.normal();
  }
  return m;
}
MatrixXd randomSpd(Eigen::Index n, Rng& rng, double floor = 0.1) {
  const MatrixXd g = gaussianMatrix(n, n, rng);
  return g * g.transpose() / static_cast<double>(n) + floor * MatrixXd::Identity(n, n);
}

// A valid scenario around the given plant, sensors and weights (one budget row, N = 1).
Scenario makeScenario(MatrixXd A, MatrixXd Q, MatrixXd P0, std::vector<SensorModel> sensors,
                      MatrixXd W, MatrixXd WT, double horizon_s) {
  Scenario s;
  s.horizon_s = horizon_s;
  s.intervals = 1;
  s.plant.m0 = VectorXd::Zero(A.rows());
  s.plant.A = std::move(A);
  s.plant.Q = std::move(Q);
  s.plant.P0 = std::move(P0);
  s.sensors = std::move(sensors);
  s.cost.W = std::move(W);
  s.cost.WT = std::move(WT);
  s.constraints.C = MatrixXd::Ones(1, static_cast<Eigen::Index>(s.sensors.size()));
  s.constraints.b = VectorXd::Ones(1);
  validateScenario(s, "test scenario");
  return s;
}

std::vector<SensorModel> randomSensors(Eigen::Index n, const std::vector<Eigen::Index>& rows,
                                       Rng& rng) {
  std::vector<SensorModel> sensors;
  for (const Eigen::Index p : rows)
    sensors.push_back({gaussianMatrix(p, n, rng), randomSpd(p, rng)});
  return sensors;
}

// The textbook update, written independently of the filter: eq. (4) and the mean update.
struct Estimate {
  VectorXd mean;
  MatrixXd covariance;
};
Estimate textbookUpdate(const Estimate& prior, const SensorModel& sensor, const VectorXd& z) {
  const MatrixXd& P = prior.covariance;
  const MatrixXd S = sensor.H * P * sensor.H.transpose() + sensor.R;
  const MatrixXd S_inv = S.inverse();
  Estimate posterior;
  posterior.covariance = P - P * sensor.H.transpose() * S_inv * sensor.H * P;
  posterior.mean = prior.mean + P * sensor.H.transpose() * S_inv * (z - sensor.H * prior.mean);
  return posterior;
}

TEST(CdKalmanFilter, BrownianCostEqualsEquation12OfTheBrownianPaper) {
  // Scalar Brownian motion (A = 0, Q = σ²), sensor k with H = 1, R = v_k, W = 1, W_T = 0,
  // measured at deterministic instants t_1 <= ... <= t_n (two at once, one at t = 0).
  const double sigma2 = 0.7;
  const double v0 = 0.5;
  const double T = 2.0;
  const std::vector<double> instants = {0.0, 0.3, 0.3, 0.9, 1.6};
  const std::vector<double> variances = {1.0, 2.0, 0.5, 3.0, 1.2};

  // Eq. (12): J = Σ_{k=0}^{n} [σ² (t_{k+1} - t_k)² / 2 + Γ_k (t_{k+1} - t_k)], t_0 = 0,
  // t_{n+1} = T, Γ_0 = v_0 and by eqs. (7) and (11) Γ_k = v_k // (Γ_{k-1} + σ² (t_k - t_{k-1})),
  // with a // b = ab / (a + b).
  const auto parallel = [](double a, double b) { return a * b / (a + b); };
  double expected = 0.0;
  double gamma = v0;
  double previous = 0.0;
  for (std::size_t k = 0; k <= instants.size(); ++k) {
    const double next = k < instants.size() ? instants[k] : T;
    const double gap = next - previous;
    expected += sigma2 * gap * gap / 2 + gamma * gap;
    if (k < instants.size()) gamma = parallel(variances[k], gamma + sigma2 * gap);
    previous = next;
  }

  std::vector<SensorModel> sensors;
  for (const double v : variances) {
    sensors.push_back({MatrixXd::Ones(1, 1), MatrixXd::Constant(1, 1, v)});
  }
  const Scenario scenario = makeScenario(MatrixXd::Zero(1, 1), MatrixXd::Constant(1, 1, sigma2),
                                         MatrixXd::Constant(1, 1, v0), sensors,
                                         MatrixXd::Ones(1, 1), MatrixXd::Zero(1, 1), T);
  CdKalmanFilter filter(scenario);
  for (std::size_t k = 0; k < instants.size(); ++k) {
    filter.propagateTo(instants[k]);
    filter.updateCovariance(static_cast<int>(k));
  }
  filter.propagateTo(T);
  EXPECT_EQ(filter.terminalCost(), 0.0);
  EXPECT_LT(relativeError(filter.cost(), expected), 1e-14)
      << filter.cost() << " vs eq. (12) " << expected;
  // And the variance at T is Γ_n + σ² (T - t_n), eq. (10).
  EXPECT_LT(relativeError(filter.covariance()(0, 0), gamma + sigma2 * (T - instants.back())),
            1e-14);
}

TEST(CdKalmanFilter, SequentialUpdatesAtOneInstantEqualOneJointUpdate) {
  Rng rng(21);
  const Eigen::Index n = 4;
  const std::vector<SensorModel> sensors = randomSensors(n, {1, 2, 1}, rng);
  // The same three sensors as one: stacked H, block-diagonal R.
  SensorModel joint{MatrixXd(4, n), MatrixXd::Zero(4, 4)};
  Eigen::Index row = 0;
  for (const SensorModel& s : sensors) {
    joint.H.middleRows(row, s.H.rows()) = s.H;
    joint.R.block(row, row, s.R.rows(), s.R.rows()) = s.R;
    row += s.H.rows();
  }
  const MatrixXd A = gaussianMatrix(n, n, rng) / 2;
  const MatrixXd Q = randomSpd(n, rng);
  const MatrixXd P0 = 10.0 * randomSpd(n, rng);
  const MatrixXd I = MatrixXd::Identity(n, n);
  CdKalmanFilter separate(makeScenario(A, Q, P0, sensors, I, I, 1.0));
  CdKalmanFilter reversed(makeScenario(A, Q, P0, sensors, I, I, 1.0));
  CdKalmanFilter together(makeScenario(A, Q, P0, {joint}, I, I, 1.0));

  const VectorXd m = gaussianMatrix(n, 1, rng);
  const VectorXd z = gaussianMatrix(4, 1, rng);
  for (CdKalmanFilter* filter : {&separate, &reversed, &together}) {
    filter->reset(0.0, m, P0);
    filter->propagateTo(0.4);
  }
  separate.update(0, z.segment(0, 1));
  separate.propagateTo(0.4);  // a no-op: arrivals at one instant
  separate.update(1, z.segment(1, 2));
  separate.update(2, z.segment(3, 1));
  reversed.update(2, z.segment(3, 1));
  reversed.update(1, z.segment(1, 2));
  reversed.update(0, z.segment(0, 1));
  together.update(0, z);

  EXPECT_LT(relativeError(separate.covariance(), together.covariance()), 1e-13);
  EXPECT_LT(relativeError(separate.mean(), together.mean()), 1e-13);
  EXPECT_LT(relativeError(reversed.covariance(), together.covariance()), 1e-13);
  EXPECT_LT(relativeError(reversed.mean(), together.mean()), 1e-13);
  EXPECT_EQ(separate.runningCost(), together.runningCost());
}

TEST(CdKalmanFilter, UpdateMatchesTheTextbookFormula) {
  Rng rng(22);
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Index n = 2 + trial % 5;
    const Eigen::Index p = 1 + (trial / 5) % n;
    const std::vector<SensorModel> sensors = randomSensors(n, {p}, rng);
    const MatrixXd I = MatrixXd::Identity(n, n);
    CdKalmanFilter filter(makeScenario(-I, I, I, sensors, I, I, 1.0));
    const Estimate prior{gaussianMatrix(n, 1, rng), randomSpd(n, rng, 0.01) * (1.0 + trial)};
    const VectorXd z = gaussianMatrix(p, 1, rng);
    const Estimate expected = textbookUpdate(prior, sensors[0], z);

    filter.reset(0.0, prior.mean, prior.covariance);
    filter.update(0, z);
    // The textbook expression itself, in double, is good to a few 1e-13 here.
    EXPECT_LT(relativeError(filter.covariance(), expected.covariance), 1e-11) << trial;
    EXPECT_LT(relativeError(filter.mean(), expected.mean), 1e-11) << trial;

    filter.reset(0.0, prior.mean, prior.covariance);
    filter.updateCovariance(0);
    EXPECT_LT(relativeError(filter.covariance(), expected.covariance), 1e-11) << trial;
    EXPECT_EQ(filter.mean(), prior.mean);
  }
}

// Brute force for a whole episode: RK4 with fine fixed steps on ṁ = A m, Ṗ = A P + P A' + Q
// and ċ = <W, P> between arrivals, the textbook update at arrivals.
struct Episode {
  Estimate estimate;
  double running_cost = 0.0;
};
void integrateFineSteps(Episode& e, const Scenario& s, double dt) {
  const MatrixXd& A = s.plant.A;
  const auto derivative = [&](const MatrixXd& P) {
    return std::pair<MatrixXd, double>(A * P + P * A.transpose() + s.plant.Q,
                                       s.cost.W.cwiseProduct(P).sum());
  };
  const int steps = 20000;
  const double h = dt / steps;
  for (int k = 0; k < steps; ++k) {
    MatrixXd& P = e.estimate.covariance;
    VectorXd& m = e.estimate.mean;
    const auto [k1, c1] = derivative(P);
    const auto [k2, c2] = derivative(P + h / 2 * k1);
    const auto [k3, c3] = derivative(P + h / 2 * k2);
    const auto [k4, c4] = derivative(P + h * k3);
    const VectorXd l1 = A * m, l2 = A * (m + h / 2 * l1), l3 = A * (m + h / 2 * l2),
                   l4 = A * (m + h * l3);
    P += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    m += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4);
    e.running_cost += h / 6 * (c1 + 2 * c2 + 2 * c3 + c4);
  }
}

TEST(CdKalmanFilter, PropagationAndCostMatchFineStepIntegrationAcrossAnEpisode) {
  Rng rng(23);
  const Eigen::Index n = 3;
  const MatrixXd A = gaussianMatrix(n, n, rng) / 2;
  const Scenario s =
      makeScenario(A, randomSpd(n, rng), 5.0 * randomSpd(n, rng), randomSensors(n, {1, 2, 1}, rng),
                   randomSpd(n, rng), randomSpd(n, rng), 2.5);
  const std::vector<std::pair<double, int>> arrivals = {
      {0.13, 0}, {0.5, 1}, {0.5, 2}, {1.2, 0}, {2.0, 2}};
  CdKalmanFilter filter(s);
  Episode reference{{s.plant.m0, s.plant.P0}, 0.0};
  double t = 0.0;
  for (const auto& [time, sensor] : arrivals) {
    const VectorXd z = gaussianMatrix(s.sensors[static_cast<std::size_t>(sensor)].H.rows(), 1, rng);
    filter.propagateTo(time);
    filter.update(sensor, z);
    if (time > t) integrateFineSteps(reference, s, time - t);
    reference.estimate =
        textbookUpdate(reference.estimate, s.sensors[static_cast<std::size_t>(sensor)], z);
    t = time;
  }
  filter.propagateTo(s.horizon_s);
  integrateFineSteps(reference, s, s.horizon_s - t);

  EXPECT_EQ(filter.time(), s.horizon_s);
  EXPECT_LT(relativeError(filter.covariance(), reference.estimate.covariance), 1e-11);
  EXPECT_LT(relativeError(filter.mean(), reference.estimate.mean), 1e-11);
  EXPECT_LT(relativeError(filter.runningCost(), reference.running_cost), 1e-11);
  const double terminal = s.cost.WT.cwiseProduct(reference.estimate.covariance).sum();
  EXPECT_LT(relativeError(filter.terminalCost(), terminal), 1e-11);
  EXPECT_LT(relativeError(filter.cost(), reference.running_cost + terminal), 1e-11);
}

TEST(CdKalmanFilter, LongRunKeepsTheCovarianceSymmetricPositiveDefinite) {
  // 10^5 random propagations and updates on the paper's n = 5, M = 30 plant, with measurement
  // noise spread over eight decades (down to R ~ 1e-6 against P0 = 100 I, where the plain
  // subtraction P - g_j(P) is most fragile). A long-double textbook filter fed the same steps
  // is the reference.
  RandomPlantSpec spec;
  spec.seed = 5;
  Scenario s = generateRandomScenario(spec);
  Rng rng(24);
  for (SensorModel& sensor : s.sensors) sensor.R *= std::pow(10.0, -6.0 + 8.0 * rng.uniform());
  s.cost.W = MatrixXd::Identity(5, 5);
  CdKalmanFilter filter(s);

  using MatrixL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  using VectorL = Eigen::Matrix<long double, Eigen::Dynamic, 1>;
  MatrixL P_ref = s.plant.P0.cast<long double>();
  VectorL m_ref = s.plant.m0.cast<long double>();

  IntervalTransition step;
  double worst_relative_gap = 0.0;
  int updates = 0;
  for (int k = 0; k < 100000; ++k) {
    if (rng.uniform() < 0.5) {
      const double dt = rng.exponential(20.0);
      filter.transition().over(dt, step);
      filter.propagateBy(step, dt);
      const MatrixL Phi = step.Phi.cast<long double>();
      P_ref = Phi * P_ref * Phi.transpose() + step.Qd.cast<long double>();
      m_ref = Phi * m_ref;
    } else {
      const int j = static_cast<int>(rng.uniform() * s.sensorCount());
      const SensorModel& sensor = s.sensors[static_cast<std::size_t>(j)];
      VectorXd z(1);
      z(0) = 10.0 * rng.normal();
      filter.update(j, z);
      const MatrixL H = sensor.H.cast<long double>();
      const MatrixL S = H * P_ref * H.transpose() + sensor.R.cast<long double>();
      const MatrixL K = P_ref * H.transpose() * S.inverse();
      m_ref += K * (z.cast<long double>() - H * m_ref);
      P_ref -= K * H * P_ref;
      P_ref = ((P_ref + P_ref.transpose()) / 2).eval();
      ++updates;
    }
    const MatrixXd& P = filter.covariance();
    ASSERT_EQ(P, P.transpose()) << "step " << k;
    ASSERT_EQ(Eigen::LLT<MatrixXd>(P).info(), Eigen::Success) << "step " << k;
    if (k % 1000 == 999) {
      const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<MatrixXd>(P).eigenvalues();
      ASSERT_GT(eig.minCoeff(), 0.0) << "step " << k;
      const MatrixXd reference = P_ref.cast<double>();
      worst_relative_gap = std::max(worst_relative_gap, relativeError(P, reference));
    }
  }
  EXPECT_GT(updates, 40000);
  EXPECT_LT(worst_relative_gap, 1e-12);
  EXPECT_TRUE(filter.mean().allFinite());
  EXPECT_LT(relativeError(filter.mean(), m_ref.cast<double>()), 1e-12);
}

TEST(CdKalmanFilter, PropagateByWithAPrecomputedStepEqualsPropagateTo) {
  RandomPlantSpec spec;
  spec.state_dim = 4;
  spec.sensor_count = 3;
  Scenario s = generateRandomScenario(spec);
  s.cost.W = MatrixXd::Identity(4, 4);
  CdKalmanFilter a(s);
  CdKalmanFilter b(s);
  a.propagateTo(0.37);
  b.propagateBy(b.transition().over(0.37), 0.37);
  EXPECT_EQ(a.covariance(), b.covariance());
  EXPECT_EQ(a.mean(), b.mean());
  EXPECT_EQ(a.runningCost(), b.runningCost());
  EXPECT_DOUBLE_EQ(a.time(), b.time());
}

TEST(CdKalmanFilter, PropagatingToTheCurrentTimeIsANoOpAndBackwardsThrows) {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 2;
  Scenario s = generateRandomScenario(spec);
  s.cost.W = MatrixXd::Identity(3, 3);
  CdKalmanFilter filter(s);
  filter.propagateTo(0.5);
  const MatrixXd P = filter.covariance();
  const double cost = filter.runningCost();
  filter.propagateTo(0.5);
  EXPECT_EQ(filter.covariance(), P);
  EXPECT_EQ(filter.runningCost(), cost);
  EXPECT_THROW(filter.propagateTo(0.4), InputError);
  EXPECT_THROW(filter.propagateTo(std::nan("")), InputError);
}

TEST(CdKalmanFilter, ResetRestoresTheInitialStateAndRestartsTheCost) {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 2;
  Scenario s = generateRandomScenario(spec);
  s.cost.W = MatrixXd::Identity(3, 3);
  s.plant.m0 = VectorXd::Constant(3, 0.25);
  CdKalmanFilter filter(s);
  EXPECT_EQ(filter.time(), 0.0);
  EXPECT_EQ(filter.covariance(), s.plant.P0);
  EXPECT_EQ(filter.mean(), s.plant.m0);
  EXPECT_EQ(filter.runningCost(), 0.0);
  // At t = 0 with nothing run yet, J is the terminal cost <W_T, P0> alone.
  EXPECT_DOUBLE_EQ(filter.cost(), s.cost.WT.cwiseProduct(s.plant.P0).sum());

  filter.propagateTo(1.0);
  filter.update(1, VectorXd::Ones(1));
  filter.reset();
  EXPECT_EQ(filter.time(), 0.0);
  EXPECT_EQ(filter.covariance(), s.plant.P0);
  EXPECT_EQ(filter.mean(), s.plant.m0);
  EXPECT_EQ(filter.runningCost(), 0.0);

  const MatrixXd P = 2.0 * MatrixXd::Identity(3, 3);
  filter.reset(1.5, VectorXd::Zero(3), P);
  EXPECT_EQ(filter.time(), 1.5);
  EXPECT_EQ(filter.runningCost(), 0.0);
  filter.propagateTo(1.5 + 1e-3);
  // Over a short interval the running cost is close to <W, P> dt.
  EXPECT_NEAR(filter.runningCost(), P.trace() * 1e-3, 1e-5);
}

TEST(CdKalmanFilter, RejectsBadSensorIndexAndMeasurementSize) {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 2;
  spec.rows_per_sensor = 2;
  CdKalmanFilter filter(generateRandomScenario(spec));
  EXPECT_THROW(filter.update(2, VectorXd::Zero(2)), InputError);
  EXPECT_THROW(filter.update(-1, VectorXd::Zero(2)), InputError);
  EXPECT_THROW(filter.updateCovariance(5), InputError);
  EXPECT_THROW(filter.update(0, VectorXd::Zero(3)), InputError);
  EXPECT_NO_THROW(filter.update(0, VectorXd::Zero(2)));
}

}  // namespace
}  // namespace sensornet
