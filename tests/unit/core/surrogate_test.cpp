#include "sensornet/core/surrogate.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/random.hpp"
#include "support/eigen_near.hpp"
#include "support/surrogate_references.hpp"

// Every reference here is computed independently of the rollout's integrator: the exact
// Hamiltonian (linear-fractional) solution of the Riccati equation, closed-form Lyapunov and
// scalar solutions, a brute-force fixed-step RK4 and Gauss-Legendre quadrature.

namespace sensornet {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using reference::covarianceFormByRk4;
using reference::Rk4Result;
using reference::exactRiccatiStep;
using reference::frobenius;
using reference::informationRate;

constexpr double kRelTol = 1e-9;  // what the default rollout tolerance (1e-10) must deliver

using testing::relativeError;

MatrixXd randomMatrix(Eigen::Index rows, Eigen::Index cols, Rng& rng) {
  MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i)
    for (Eigen::Index j = 0; j < cols; ++j) m(i, j) = rng.normal();
  return m;
}
MatrixXd randomPositiveDefinite(Eigen::Index n, Rng& rng, double floor = 0.1) {
  const MatrixXd b = randomMatrix(n, n, rng);
  return b * b.transpose() / static_cast<double>(n) + floor * MatrixXd::Identity(n, n);
}

// Rates in [0, 1) with about zero_fraction of them switched off, each interval scaled to use a
// random share of its budget: C λ <= b, λ >= 0.
RateSchedule randomFeasibleSchedule(const Scenario& s, Rng& rng, double zero_fraction = 0.3) {
  MatrixXd rates(s.intervals, s.sensorCount());
  for (int k = 0; k < s.intervals; ++k) {
    for (int j = 0; j < s.sensorCount(); ++j) {
      rates(k, j) = rng.uniform() < zero_fraction ? 0.0 : rng.uniform();
    }
    const VectorXd load = s.constraints.C * rates.row(k).transpose();
    double scale = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < load.size(); ++i) {
      if (load(i) > 0.0) scale = std::min(scale, s.constraints.b(i) / load(i));
    }
    if (std::isfinite(scale)) rates.row(k) *= scale * (0.2 + 0.8 * rng.uniform());
  }
  RateSchedule schedule(s.horizon_s, rates);
  EXPECT_TRUE(checkFeasibility(schedule, s).feasible);
  return schedule;
}

Scenario smallScenario(std::uint64_t seed, int n, int m, int rows, double noise_scale,
                       double horizon_s, int intervals) {
  RandomPlantSpec spec;
  spec.state_dim = n;
  spec.sensor_count = m;
  spec.rows_per_sensor = rows;
  spec.seed = seed;
  spec.noise_scale = noise_scale;
  spec.horizon_s = horizon_s;
  spec.intervals = intervals;
  return generateRandomScenario(spec);
}

// Gauss-Legendre nodes and weights on [-1, 1] by Newton's method on P_m.
struct Quadrature {
  VectorXd nodes, weights;
};
Quadrature gaussLegendre(int m) {
  Quadrature q{VectorXd(m), VectorXd(m)};
  for (int i = 0; i < m; ++i) {
    double x = std::cos(std::numbers::pi * (i + 0.75) / (m + 0.5));
    double derivative = 0.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= m; ++k) {
        const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      derivative = m * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / derivative;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    q.nodes(i) = x;
    q.weights(i) = 2.0 / ((1.0 - x * x) * derivative * derivative);
  }
  return q;
}

// Interval boundaries of a rollout from 0: k T / N.
void expectBoundaryTimes(const SurrogateRollout& r, const RateSchedule& schedule) {
  ASSERT_EQ(r.times.size(), static_cast<std::size_t>(schedule.intervals() + 1));
  ASSERT_EQ(r.covariances.size(), r.times.size());
  for (int k = 0; k <= schedule.intervals(); ++k) {
    EXPECT_NEAR(r.times[static_cast<std::size_t>(k)], k * schedule.intervalLength(), 1e-14);
  }
  EXPECT_EQ(r.times.back(), schedule.horizon());
}

// ---------------------------------------------------------------------------------------------
// Information form, eq. (11)

TEST(InformationForm, MatchesTheExactRiccatiSolutionAtEveryBoundary) {
  struct Case {
    std::uint64_t seed;
    int n, m, rows;
    double noise_scale;
  };
  for (const Case c : {Case{1, 4, 6, 1, 1.0}, Case{2, 3, 5, 2, 1e-2}, Case{3, 5, 8, 1, 1e2},
                       Case{4, 2, 3, 2, 0.1}}) {
    SCOPED_TRACE("seed " + std::to_string(c.seed));
    const Scenario s = smallScenario(c.seed, c.n, c.m, c.rows, c.noise_scale, 2.0, 8);
    Rng rng = Rng::keyed(c.seed, 11);
    const RateSchedule schedule = randomFeasibleSchedule(s, rng);
    const SurrogateRollout r = rolloutInformationForm(s, schedule);
    expectBoundaryTimes(r, schedule);

    MatrixXd exact = s.plant.P0;
    for (int k = 0; k < schedule.intervals(); ++k) {
      exact = exactRiccatiStep(s.plant.A, s.plant.Q, informationRate(s, schedule, k), exact,
                               schedule.intervalLength());
      const MatrixXd& p = r.covariances[static_cast<std::size_t>(k + 1)];
      EXPECT_LT(relativeError(p, exact), kRelTol) << "boundary " << k + 1;
      EXPECT_MATRIX_NEAR(p, p.transpose(), 0.0);  // exactly symmetric
    }
    EXPECT_EQ(r.running_cost, 0.0);  // W = 0 in the paper's protocol
    EXPECT_LT(relativeError(r.terminal_cost, exact.trace()), kRelTol);
    EXPECT_EQ(r.cost, r.terminal_cost);
    EXPECT_GT(r.steps, 0);
  }
}

TEST(InformationForm, RunningCostMatchesGaussLegendreQuadratureOfTheExactSolution) {
  Scenario s = smallScenario(7, 4, 6, 1, 0.5, 1.5, 5);
  Rng rng = Rng::keyed(7, 12);
  s.cost.W = randomPositiveDefinite(4, rng, 0.0);
  s.cost.WT = randomPositiveDefinite(4, rng, 0.0);
  const RateSchedule schedule = randomFeasibleSchedule(s, rng);
  const SurrogateRollout r = rolloutInformationForm(s, schedule);

  // 12 Gauss-Legendre points on each of 11 panels per interval, P at every node from the exact
  // solution. After a rate jump P moves fast (it is rational in t, with a pole just before the
  // interval start when P >> R), so the panels are graded geometrically toward the start:
  // [0, h/1024], [h/1024, h/512], ..., [h/2, h]. Uniform panels converge too slowly here.
  const Quadrature gl = gaussLegendre(12);
  const double length = schedule.intervalLength();
  double running = 0.0;
  MatrixXd start = s.plant.P0;
  for (int k = 0; k < schedule.intervals(); ++k) {
    const MatrixXd U = informationRate(s, schedule, k);
    double from = 0.0;
    for (int level = 10; level >= 0; --level) {
      const double to = length * std::ldexp(1.0, -level);
      for (int i = 0; i < gl.nodes.size(); ++i) {
        const double offset = from + 0.5 * (to - from) * (gl.nodes(i) + 1.0);
        const MatrixXd p = exactRiccatiStep(s.plant.A, s.plant.Q, U, start, offset);
        running += 0.5 * (to - from) * gl.weights(i) * frobenius(s.cost.W, p);
      }
      from = to;
    }
    start = exactRiccatiStep(s.plant.A, s.plant.Q, U, start, length);
  }
  EXPECT_LT(relativeError(r.running_cost, running), kRelTol);
  EXPECT_LT(relativeError(r.terminal_cost, frobenius(s.cost.WT, start)), kRelTol);
  EXPECT_DOUBLE_EQ(r.cost, r.running_cost + r.terminal_cost);
}

TEST(InformationForm, StartsMidIntervalFromAGivenCovariance) {
  const Scenario s = smallScenario(9, 3, 4, 1, 1.0, 2.0, 8);
  Rng rng = Rng::keyed(9, 13);
  const RateSchedule schedule = randomFeasibleSchedule(s, rng);
  RolloutOptions options;
  options.start_time = 1.1;  // inside interval 4 = [1.0, 1.25)
  options.start_covariance = randomPositiveDefinite(3, rng);
  const SurrogateRollout r = rolloutInformationForm(s, schedule, options);

  ASSERT_EQ(r.times.size(), 5u);  // 1.1, 1.25, 1.5, 1.75, 2.0
  EXPECT_EQ(r.times.front(), 1.1);
  EXPECT_NEAR(r.times[1], 1.25, 1e-15);
  EXPECT_EQ(r.times.back(), 2.0);
  EXPECT_EQ(r.covariances.front(), *options.start_covariance);

  MatrixXd exact = exactRiccatiStep(s.plant.A, s.plant.Q, informationRate(s, schedule, 4),
                                    *options.start_covariance, 0.15);
  EXPECT_LT(relativeError(r.covariances[1], exact), kRelTol);
  for (int k = 5; k < 8; ++k) {
    exact = exactRiccatiStep(s.plant.A, s.plant.Q, informationRate(s, schedule, k), exact, 0.25);
  }
  EXPECT_LT(relativeError(r.covariances.back(), exact), kRelTol);
  EXPECT_LT(relativeError(r.cost, exact.trace()), kRelTol);
}

// A prediction over [1.1, 1.6]: interval 4 from 1.1, then interval 5 up to mid-interval 1.6.
TEST(InformationForm, StopsAtAnEndTimeInsideAnInterval) {
  const Scenario s = smallScenario(9, 3, 4, 1, 1.0, 2.0, 8);
  Rng rng = Rng::keyed(9, 14);
  const RateSchedule schedule = randomFeasibleSchedule(s, rng);
  RolloutOptions options;
  options.start_time = 1.1;
  options.end_time = 1.6;  // inside interval 6 = [1.5, 1.75)
  options.start_covariance = randomPositiveDefinite(3, rng);
  const SurrogateRollout r = rolloutInformationForm(s, schedule, options);

  ASSERT_EQ(r.times.size(), 4u);  // 1.1, 1.25, 1.5, 1.6
  EXPECT_EQ(r.times.back(), 1.6);
  MatrixXd exact = exactRiccatiStep(s.plant.A, s.plant.Q, informationRate(s, schedule, 4),
                                    *options.start_covariance, 0.15);
  exact = exactRiccatiStep(s.plant.A, s.plant.Q, informationRate(s, schedule, 5), exact, 0.25);
  exact = exactRiccatiStep(s.plant.A, s.plant.Q, informationRate(s, schedule, 6), exact, 0.1);
  EXPECT_LT(relativeError(r.covariances.back(), exact), kRelTol);
  EXPECT_EQ(r.terminal_cost, 0.0) << "no terminal term before T";
}

// ---------------------------------------------------------------------------------------------
// Covariance form, eq. (15)

TEST(CovarianceForm, MatchesABruteForceFineStepRk4) {
  struct Case {
    std::uint64_t seed;
    int n, m, rows;
    double noise_scale;
  };
  for (const Case c : {Case{21, 3, 5, 1, 1.0}, Case{22, 3, 4, 2, 0.3}}) {
    SCOPED_TRACE("seed " + std::to_string(c.seed));
    Scenario s = smallScenario(c.seed, c.n, c.m, c.rows, c.noise_scale, 1.0, 4);
    Rng rng = Rng::keyed(c.seed, 14);
    s.cost.W = randomPositiveDefinite(c.n, rng, 0.0);
    const RateSchedule schedule = randomFeasibleSchedule(s, rng, 0.2);
    const SurrogateRollout r = rolloutCovarianceForm(s, schedule);
    expectBoundaryTimes(r, schedule);

    // Step 6.25e-4; the comparison does not change between 250 and 1000 steps per interval.
    const Rk4Result reference = covarianceFormByRk4(s, schedule, 400);
    for (std::size_t k = 1; k < reference.boundaries.size(); ++k) {
      EXPECT_LT(relativeError(r.covariances[k], reference.boundaries[k]), kRelTol)
          << "boundary " << k;
      EXPECT_MATRIX_NEAR(r.covariances[k], r.covariances[k].transpose(), 0.0);
    }
    EXPECT_LT(relativeError(r.running_cost, reference.running_cost), kRelTol);
    EXPECT_LT(relativeError(r.terminal_cost, reference.boundaries.back().trace()), kRelTol);
  }
}

// One scalar state and one scalar sensor: ṗ = 2ap + q - λ h² p² / (h² p + r). With
// N(p) = (2ap + q)(h²p + r) - λh²p² = α(p - p1)(p - p2), the time to go from p_a to p_b is
// ∫ (h²p + r) / N(p) dp = c1 ln((p_b - p1)/(p_a - p1)) + c2 ln((p_b - p2)/(p_a - p2)),
// which is monotone in p_b between p_a and the equilibrium, so bisection inverts it.
double scalarCovarianceStep(double a, double q, double h, double r, double lambda, double p,
                            double duration) {
  const double alpha = h * h * (2.0 * a - lambda);  // < 0 when λ > 2a: one positive root
  const double beta = 2.0 * a * r + q * h * h;
  const double gamma = q * r;
  const double root = std::sqrt(beta * beta - 4.0 * alpha * gamma);
  const double p1 = (-beta - root) / (2.0 * alpha);  // the positive root: the equilibrium
  const double p2 = (-beta + root) / (2.0 * alpha);
  const double c1 = (h * h * p1 + r) / (alpha * (p1 - p2));
  const double c2 = (h * h * p2 + r) / (alpha * (p2 - p1));
  auto elapsed = [&](double pb) {
    return c1 * std::log((pb - p1) / (p - p1)) + c2 * std::log((pb - p2) / (p - p2));
  };
  double lo = std::min(p, p1), hi = std::max(p, p1);
  for (int i = 0; i < 200 && hi - lo > 0.0; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (mid == lo || mid == hi) break;
    // Farther from p (toward the equilibrium) takes longer.
    const bool too_far = elapsed(mid) > duration;
    if ((p > p1) == too_far) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

TEST(CovarianceForm, ScalarSensorMatchesTheClosedFormTimeIntegral) {
  const double a = 0.4, q = 0.7, h = 1.3, noise = 0.5;
  Scenario s;
  s.horizon_s = 2.0;
  s.intervals = 4;
  s.plant.A = MatrixXd::Constant(1, 1, a);
  s.plant.Q = MatrixXd::Constant(1, 1, q);
  s.plant.P0 = MatrixXd::Constant(1, 1, 20.0);
  s.plant.m0 = VectorXd::Zero(1);
  s.sensors.push_back({MatrixXd::Constant(1, 1, h), MatrixXd::Constant(1, 1, noise)});
  s.cost.W = MatrixXd::Zero(1, 1);
  s.cost.WT = MatrixXd::Identity(1, 1);
  s.constraints.C = MatrixXd::Ones(1, 1);
  s.constraints.b = VectorXd::Constant(1, 5.0);
  validateScenario(s, "scalar test");
  const VectorXd lambda = (VectorXd(4) << 1.5, 3.0, 0.9, 2.2).finished();  // all > 2a
  const RateSchedule schedule(2.0, lambda);

  const SurrogateRollout result = rolloutCovarianceForm(s, schedule);
  double p = 20.0;
  for (int k = 0; k < 4; ++k) {
    p = scalarCovarianceStep(a, q, h, noise, lambda(k), p, 0.5);
    EXPECT_LT(relativeError(result.covariances[static_cast<std::size_t>(k + 1)](0, 0), p), kRelTol)
        << "boundary " << k + 1 << ", exact " << p;
  }
  EXPECT_LT(relativeError(result.cost, p), kRelTol);
}

// ---------------------------------------------------------------------------------------------
// Both forms

// A diagonal plant, full Q, P0, W, W_T: the Lyapunov flow Ṗ = A P + P A' + Q has the entrywise
// closed form P_ij(t) = e^{s t} P0_ij + Q_ij (e^{s t} - 1)/s with s = a_i + a_j.
struct DiagonalPlant {
  Scenario scenario;
  VectorXd modes;
};
DiagonalPlant diagonalPlant() {
  DiagonalPlant d;
  d.modes = Eigen::Vector3d(-0.7, 0.3, 0.45);
  Rng rng(31);
  Scenario& s = d.scenario;
  s.horizon_s = 2.0;
  s.intervals = 5;
  s.plant.A = d.modes.asDiagonal();
  s.plant.Q = randomPositiveDefinite(3, rng);
  s.plant.P0 = randomPositiveDefinite(3, rng, 1.0);
  s.plant.m0 = VectorXd::Zero(3);
  s.sensors.push_back({randomMatrix(3, 3, rng), randomPositiveDefinite(3, rng, 0.5)});
  s.cost.W = randomPositiveDefinite(3, rng, 0.0);
  s.cost.WT = randomPositiveDefinite(3, rng, 0.0);
  s.constraints.C = MatrixXd::Ones(1, 1);
  s.constraints.b = VectorXd::Constant(1, 2.0);
  validateScenario(s, "diagonal plant");
  return d;
}

MatrixXd lyapunovAt(const DiagonalPlant& d, double t) {
  const Scenario& s = d.scenario;
  MatrixXd p(3, 3);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double rate = d.modes(i) + d.modes(j);
      p(i, j) =
          std::exp(rate * t) * s.plant.P0(i, j) + s.plant.Q(i, j) * std::expm1(rate * t) / rate;
    }
  }
  return p;
}

// ∫_0^T <W, P(t)> dt entrywise: P0_ij (e^{sT} - 1)/s + Q_ij ((e^{sT} - 1)/s - T)/s.
double lyapunovRunningCost(const DiagonalPlant& d) {
  const Scenario& s = d.scenario;
  const double T = s.horizon_s;
  double cost = 0.0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double rate = d.modes(i) + d.modes(j);
      const double growth = std::expm1(rate * T) / rate;
      cost += s.cost.W(i, j) * (s.plant.P0(i, j) * growth + s.plant.Q(i, j) * (growth - T) / rate);
    }
  }
  return cost;
}

TEST(Surrogates, BothReduceToTheLyapunovFlowWithoutMeasurements) {
  const DiagonalPlant d = diagonalPlant();
  const Scenario& s = d.scenario;
  const RateSchedule silent(s.horizon_s, MatrixXd::Zero(s.intervals, 1));
  const double running = lyapunovRunningCost(d);
  const MatrixXd terminal = lyapunovAt(d, s.horizon_s);
  for (const SurrogateForm form : {SurrogateForm::Information, SurrogateForm::Covariance}) {
    SCOPED_TRACE(form == SurrogateForm::Information ? "information" : "covariance");
    const SurrogateRollout r = rollout(form, s, silent);
    for (std::size_t k = 0; k < r.times.size(); ++k) {
      EXPECT_LT(relativeError(r.covariances[k], lyapunovAt(d, r.times[k])), kRelTol);
    }
    EXPECT_LT(relativeError(r.running_cost, running), kRelTol);
    EXPECT_LT(relativeError(r.terminal_cost, frobenius(s.cost.WT, terminal)), kRelTol);
  }
}

TEST(Surrogates, BothPredictTheLyapunovFlowUpToAnEndTime) {
  const DiagonalPlant d = diagonalPlant();
  const Scenario& s = d.scenario;
  const RateSchedule silent(s.horizon_s, MatrixXd::Zero(s.intervals, 1));
  RolloutOptions options;
  options.end_time = 0.37 * s.horizon_s;  // not on a boundary
  for (const SurrogateForm form : {SurrogateForm::Information, SurrogateForm::Covariance}) {
    SCOPED_TRACE(form == SurrogateForm::Information ? "information" : "covariance");
    const SurrogateRollout r = rollout(form, s, silent, options);
    EXPECT_EQ(r.times.back(), *options.end_time);
    EXPECT_LT(relativeError(r.covariances.back(), lyapunovAt(d, *options.end_time)), kRelTol);
  }
}

TEST(Surrogates, AgreeWithEachOtherWhenTheScheduleIsZero) {
  // One sensor seeing the whole state (p = n), switched off: no measurement, so both forms are
  // the same Lyapunov flow, reached through different state variables (Ys versus Ps).
  Scenario s = smallScenario(41, 4, 1, 4, 1.0, 3.0, 6);
  Rng rng = Rng::keyed(41, 15);
  s.cost.W = randomPositiveDefinite(4, rng, 0.0);
  const RateSchedule silent(s.horizon_s, MatrixXd::Zero(s.intervals, 1));
  const SurrogateRollout info = rolloutInformationForm(s, silent);
  const SurrogateRollout cov = rolloutCovarianceForm(s, silent);
  ASSERT_EQ(info.times, cov.times);
  for (std::size_t k = 0; k < info.times.size(); ++k) {
    EXPECT_LT(relativeError(info.covariances[k], cov.covariances[k]), kRelTol);
  }
  EXPECT_LT(relativeError(info.cost, cov.cost), kRelTol);
  const CostBracket bracket = computeBracket(s, silent);
  EXPECT_LT(relativeError(bracket.info, bracket.cov), kRelTol);
}

// dJ/dε at ε = 0 for a constant rate ε of the single sensor: the first-order change of P is
// -∫ e^{A(t-u)} G(u) e^{A'(t-u)} du with G = g(P_L) (covariance form) or P_L S P_L
// (information form), so dJ/dε = -∫_0^T <Λ(u), G(u)> du with the adjoint
// Λ(u) = e^{A'(T-u)} W_T e^{A(T-u)} + ∫_u^T e^{A'(v-u)} W e^{A(v-u)} dv, in closed form for a
// diagonal A.
double firstOrderCostChange(const DiagonalPlant& d, SurrogateForm form) {
  const Scenario& s = d.scenario;
  const auto& sensor = s.sensors.front();
  const double T = s.horizon_s;
  auto adjoint = [&](double u) {
    MatrixXd lambda(3, 3);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const double rate = d.modes(i) + d.modes(j);
        lambda(i, j) = std::exp(rate * (T - u)) * s.cost.WT(i, j) +
                       s.cost.W(i, j) * std::expm1(rate * (T - u)) / rate;
      }
    }
    return lambda;
  };
  auto reduction = [&](double u) -> MatrixXd {
    const MatrixXd p = lyapunovAt(d, u);
    if (form == SurrogateForm::Information) {
      return p * sensor.H.transpose() * sensor.R.inverse() * sensor.H * p;
    }
    const MatrixXd innovation = sensor.H * p * sensor.H.transpose() + sensor.R;
    return p * sensor.H.transpose() * innovation.inverse() * sensor.H * p;
  };
  const Quadrature gl = gaussLegendre(16);
  const int panels = 8;
  const double h = T / panels;
  double derivative = 0.0;
  for (int panel = 0; panel < panels; ++panel) {
    for (int i = 0; i < gl.nodes.size(); ++i) {
      const double u = panel * h + 0.5 * h * (gl.nodes(i) + 1.0);
      derivative -= 0.5 * h * gl.weights(i) * frobenius(adjoint(u), reduction(u));
    }
  }
  return derivative;
}

TEST(Surrogates, AgreeToFirstOrderInTinyRates) {
  const DiagonalPlant d = diagonalPlant();
  const Scenario& s = d.scenario;
  const RateSchedule silent(s.horizon_s, MatrixXd::Zero(s.intervals, 1));
  const double epsilon = 1e-6;
  const RateSchedule tiny(s.horizon_s, MatrixXd::Constant(s.intervals, 1, epsilon));
  const double lyapunov = rolloutCovarianceForm(s, silent).cost;
  const double info_slope = firstOrderCostChange(d, SurrogateForm::Information);
  const double cov_slope = firstOrderCostChange(d, SurrogateForm::Covariance);
  // The forms differ at first order (P S P versus g(P)), so this test can tell them apart.
  ASSERT_GT(std::abs(info_slope - cov_slope), 0.1 * std::abs(cov_slope));

  const CostBracket bracket = computeBracket(s, tiny);
  // J(ε) = J(0) + ε J'(0) + O(ε²): the remainder relative to the first-order term is O(ε),
  // measured as about 48 ε (information form, large P makes P S P strongly curved) and 0.74 ε
  // (covariance form) for this plant.
  EXPECT_LT(relativeError((bracket.info - lyapunov) / epsilon, info_slope), 2e-4);
  EXPECT_LT(relativeError((bracket.cov - lyapunov) / epsilon, cov_slope), 2e-4);
  EXPECT_LT(bracket.info, bracket.cov);
}

TEST(Surrogates, ARolloutSplitAtABoundaryEqualsTheWholeRollout) {
  Scenario s = smallScenario(51, 4, 7, 1, 0.5, 3.0, 12);
  Rng rng = Rng::keyed(51, 16);
  s.cost.W = randomPositiveDefinite(4, rng, 0.0);
  const RateSchedule schedule = randomFeasibleSchedule(s, rng);
  const int split = 5;
  const double t0 = split * schedule.intervalLength();

  // The head is the same problem on the horizon [0, t0].
  Scenario head_scenario = s;
  head_scenario.horizon_s = t0;
  head_scenario.intervals = split;
  const RateSchedule head_schedule(t0, schedule.rates().topRows(split));

  for (const SurrogateForm form : {SurrogateForm::Information, SurrogateForm::Covariance}) {
    SCOPED_TRACE(form == SurrogateForm::Information ? "information" : "covariance");
    const SurrogateRollout whole = rollout(form, s, schedule);
    const SurrogateRollout head = rollout(form, head_scenario, head_schedule);
    RolloutOptions rest;
    rest.start_time = t0;
    rest.start_covariance = head.covariances.back();
    const SurrogateRollout tail = rollout(form, s, schedule, rest);

    ASSERT_EQ(tail.times.size(), static_cast<std::size_t>(s.intervals - split + 1));
    EXPECT_EQ(tail.times.front(), t0);
    EXPECT_EQ(tail.times.back(), s.horizon_s);
    EXPECT_LT(relativeError(head.covariances.back(), whole.covariances[split]), kRelTol);
    EXPECT_LT(relativeError(tail.covariances.back(), whole.covariances.back()), kRelTol);
    EXPECT_LT(relativeError(head.running_cost + tail.running_cost, whole.running_cost), kRelTol);
    EXPECT_LT(relativeError(tail.terminal_cost, whole.terminal_cost), kRelTol);
  }
}

TEST(Surrogates, StartingAtTheHorizonCostsOnlyTheTerminalTerm) {
  const Scenario s = smallScenario(61, 3, 2, 1, 1.0, 1.0, 4);
  const RateSchedule schedule = uniformSchedule(s);
  RolloutOptions options;
  options.start_time = s.horizon_s;
  options.start_covariance = 2.0 * MatrixXd::Identity(3, 3);
  for (const SurrogateForm form : {SurrogateForm::Information, SurrogateForm::Covariance}) {
    const SurrogateRollout r = rollout(form, s, schedule, options);
    ASSERT_EQ(r.times.size(), 1u);
    EXPECT_EQ(r.steps, 0);
    EXPECT_EQ(r.running_cost, 0.0);
    EXPECT_DOUBLE_EQ(r.cost, 6.0);  // <I, 2 I> with n = 3
  }
}

// ---------------------------------------------------------------------------------------------
// The bracket, Corollary 1

TEST(Bracket, InformationFormNeverExceedsCovarianceFormOnRandomScenarios) {
  Rng rng(2024);
  for (int trial = 0; trial < 32; ++trial) {
    const int n = 2 + trial % 7;                             // 2..8
    const int m = 1 + static_cast<int>(rng.uniform() * 30);  // 1..30
    const int rows = (trial % 4 == 3) ? std::min(n, 2) : 1;
    const double noise_scale = std::pow(10.0, -2.0 + 4.0 * rng.uniform());  // 1e-2..1e2
    Scenario s =
        smallScenario(100 + static_cast<std::uint64_t>(trial), n, m, rows, noise_scale, 3.0, 8);
    if (trial % 2 == 1) s.cost.W = randomPositiveDefinite(n, rng, 0.0);
    const RateSchedule schedule = randomFeasibleSchedule(s, rng, 0.5 * rng.uniform());
    SCOPED_TRACE("trial " + std::to_string(trial) + ": n " + std::to_string(n) + ", M " +
                 std::to_string(m) + ", noise scale " + std::to_string(noise_scale));

    const SurrogateRollout info = rolloutInformationForm(s, schedule);
    const SurrogateRollout cov = rolloutCovarianceForm(s, schedule);
    if (trial < 3) {
      const CostBracket bracket = computeBracket(s, schedule);
      EXPECT_EQ(bracket.info, info.cost);
      EXPECT_EQ(bracket.cov, cov.cost);
    }
    // Theorem 2: P_info(t) <= Ps(t) in the Loewner order, at every boundary, up to the
    // integration tolerance relative to the covariance.
    for (std::size_t k = 0; k < info.times.size(); ++k) {
      const MatrixXd gap = cov.covariances[k] - info.covariances[k];
      const double smallest = Eigen::SelfAdjointEigenSolver<MatrixXd>(gap).eigenvalues()(0);
      EXPECT_GE(smallest, -1e-9 * cov.covariances[k].norm()) << "boundary " << k;
    }
    EXPECT_LE(info.running_cost, cov.running_cost * (1.0 + 1e-9));
    EXPECT_LE(info.cost, cov.cost * (1.0 + 1e-9));
  }
}

// ---------------------------------------------------------------------------------------------
// Bad input

std::string fieldOfError(const std::function<void()>& call) {
  try {
    call();
  } catch (const InputError& e) {
    return e.field();
  }
  return "(no InputError)";
}

TEST(RolloutInput, RejectsAScheduleThatDoesNotFitTheScenario) {
  const Scenario s = smallScenario(71, 3, 4, 1, 1.0, 2.0, 4);
  const RateSchedule fewer(2.0, MatrixXd::Ones(4, 3));
  EXPECT_EQ(fieldOfError([&] { (void)rolloutInformationForm(s, fewer); }), "schedule");
  const RateSchedule longer(2.5, MatrixXd::Ones(4, 4));
  EXPECT_EQ(fieldOfError([&] { (void)rolloutCovarianceForm(s, longer); }), "schedule.horizon");
  MatrixXd rates = MatrixXd::Ones(4, 4);
  rates(2, 1) = -0.5;
  EXPECT_EQ(fieldOfError([&] { (void)computeBracket(s, RateSchedule(2.0, rates)); }),
            "schedule.rates[2][1]");
  rates(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(fieldOfError([&] { (void)computeBracket(s, RateSchedule(2.0, rates)); }),
            "schedule.rates[2][1]");
}

TEST(RolloutInput, RejectsAScenarioWithMismatchedShapes) {
  Scenario s = smallScenario(73, 3, 2, 1, 1.0, 2.0, 4);
  s.sensors[1].R = MatrixXd::Identity(2, 2);
  const RateSchedule schedule = uniformSchedule(s);
  EXPECT_EQ(fieldOfError([&] { (void)rolloutCovarianceForm(s, schedule); }), "sensors[1].R");
  s = smallScenario(73, 3, 2, 1, 1.0, 2.0, 4);
  s.cost.WT = MatrixXd::Identity(2, 2);
  EXPECT_EQ(fieldOfError([&] { (void)rolloutInformationForm(s, schedule); }), "cost.WT");
}

TEST(RolloutInput, RejectsBadOptions) {
  const Scenario s = smallScenario(72, 3, 4, 1, 1.0, 2.0, 4);
  const RateSchedule schedule = uniformSchedule(s);
  auto fieldFor = [&](const RolloutOptions& options) {
    return fieldOfError([&] { (void)rolloutInformationForm(s, schedule, options); });
  };
  RolloutOptions options;
  options.start_time = -0.1;
  EXPECT_EQ(fieldFor(options), "options.start_time");
  options.start_time = 2.1;
  EXPECT_EQ(fieldFor(options), "options.start_time");
  options.start_time = 1.0;  // later than 0 with no covariance given
  EXPECT_EQ(fieldFor(options), "options.start_covariance");
  options.start_covariance = MatrixXd::Identity(2, 2);
  EXPECT_EQ(fieldFor(options), "options.start_covariance");
  options.start_covariance = (MatrixXd(3, 3) << 1, 0, 0, 0, 1, 0, 0, 0, -1).finished();
  EXPECT_EQ(fieldFor(options), "options.start_covariance");
  options.start_covariance = (MatrixXd(3, 3) << 1, 0.5, 0, 0, 1, 0, 0, 0, 1).finished();
  EXPECT_EQ(fieldFor(options), "options.start_covariance");
  options.start_covariance = MatrixXd::Identity(3, 3);
  EXPECT_NO_THROW((void)rolloutInformationForm(s, schedule, options));
  options.end_time = 0.5;  // before start_time
  EXPECT_EQ(fieldFor(options), "options.end_time");
  options.end_time = 2.5;  // past T
  EXPECT_EQ(fieldFor(options), "options.end_time");
  options.end_time = 2.0;
  EXPECT_NO_THROW((void)rolloutInformationForm(s, schedule, options));
  options.relative_tolerance = 0.0;
  EXPECT_EQ(fieldFor(options), "options.relative_tolerance");
  options.relative_tolerance = 1e-8;
  options.absolute_tolerance = -1.0;
  EXPECT_EQ(fieldFor(options), "options.absolute_tolerance");
}

}  // namespace
}  // namespace sensornet
