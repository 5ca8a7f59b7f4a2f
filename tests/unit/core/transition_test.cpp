#include "sensornet/core/transition.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/random.hpp"
#include "support/eigen_near.hpp"

namespace sensornet {
namespace {

using Eigen::MatrixXd;

using testing::relativeError;

MatrixXd gaussianMatrix(Eigen::Index rows, Eigen::Index cols, Rng& rng) {
  MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) m(i, j) = rng.normal();
  }
  return m;
}
MatrixXd randomSpd(Eigen::Index n, Rng& rng) {
  const MatrixXd g = gaussianMatrix(n, n, rng);
  return g * g.transpose() / static_cast<double>(n) + 0.1 * MatrixXd::Identity(n, n);
}
MatrixXd randomPsdRankOne(Eigen::Index n, Rng& rng) {
  const MatrixXd v = gaussianMatrix(n, 1, rng);
  return v * v.transpose();
}

// Brute force, independent of the code under test: classical RK4 with fixed steps on
//   Φ' = A Φ,  Qd' = A Qd + Qd A' + Q,  G' = Φ' W Φ,  P' = A P + P A' + Q,
//   noise' = <W, Qd>,  cost' = <W, P>,
// from Φ = I, Qd = G = 0, P = P0. With h ||A|| <= 5e-4 the truncation error is ~1e-13 relative.
struct Flow {
  MatrixXd Phi, Qd, G, P;
  double noise = 0.0;
  double cost = 0.0;
};

Flow flowDerivative(const Flow& y, const MatrixXd& A, const MatrixXd& Q, const MatrixXd& W) {
  Flow d;
  d.Phi = A * y.Phi;
  d.Qd = A * y.Qd + y.Qd * A.transpose() + Q;
  d.G = y.Phi.transpose() * W * y.Phi;
  d.P = A * y.P + y.P * A.transpose() + Q;
  d.noise = W.cwiseProduct(y.Qd).sum();
  d.cost = W.cwiseProduct(y.P).sum();
  return d;
}

Flow plusScaled(const Flow& y, double h, const Flow& d) {
  return {y.Phi + h * d.Phi, y.Qd + h * d.Qd,       y.G + h * d.G,
          y.P + h * d.P,     y.noise + h * d.noise, y.cost + h * d.cost};
}

Flow integrateFineSteps(const MatrixXd& A, const MatrixXd& Q, const MatrixXd& W, const MatrixXd& P0,
                        double dt) {
  const Eigen::Index n = A.rows();
  const double stiffness = std::max(1.0, A.norm() * dt);
  const int steps = std::clamp(static_cast<int>(std::ceil(2000.0 * stiffness)), 2000, 40000);
  const double h = dt / steps;
  Flow y{MatrixXd::Identity(n, n), MatrixXd::Zero(n, n), MatrixXd::Zero(n, n), P0, 0.0, 0.0};
  for (int k = 0; k < steps; ++k) {
    const Flow k1 = flowDerivative(y, A, Q, W);
    const Flow k2 = flowDerivative(plusScaled(y, h / 2, k1), A, Q, W);
    const Flow k3 = flowDerivative(plusScaled(y, h / 2, k2), A, Q, W);
    const Flow k4 = flowDerivative(plusScaled(y, h, k3), A, Q, W);
    y.Phi += h / 6 * (k1.Phi + 2 * k2.Phi + 2 * k3.Phi + k4.Phi);
    y.Qd += h / 6 * (k1.Qd + 2 * k2.Qd + 2 * k3.Qd + k4.Qd);
    y.G += h / 6 * (k1.G + 2 * k2.G + 2 * k3.G + k4.G);
    y.P += h / 6 * (k1.P + 2 * k2.P + 2 * k3.P + k4.P);
    y.noise += h / 6 * (k1.noise + 2 * k2.noise + 2 * k3.noise + k4.noise);
    y.cost += h / 6 * (k1.cost + 2 * k2.cost + 2 * k3.cost + k4.cost);
  }
  return y;
}

// Checks every output of over(dt), and the cost identity
//   ∫_0^dt <W, P(s)> ds = <P0, G> + noise_cost,  P(dt) = Phi P0 Phi' + Qd,
// against the fine-step integration, to a relative tolerance.
void expectMatchesFineSteps(const LtiTransition& transition, const MatrixXd& A, const MatrixXd& Q,
                            const MatrixXd& W, double dt, double tolerance,
                            const std::string& label) {
  Rng rng = Rng::keyed(99, static_cast<std::uint64_t>(A.rows()));
  const MatrixXd P0 = randomSpd(A.rows(), rng);
  const Flow reference = integrateFineSteps(A, Q, W, P0, dt);
  const IntervalTransition step = transition.over(dt);
  const std::string where = label + ", dt = " + std::to_string(dt);
  EXPECT_LT(relativeError(step.Phi, reference.Phi), tolerance) << where;
  EXPECT_LT(relativeError(step.Qd, reference.Qd), tolerance) << where;
  EXPECT_LT(relativeError(step.cost_gramian, reference.G), tolerance) << where;
  EXPECT_LT(relativeError(step.noise_cost, reference.noise), tolerance) << where;
  const MatrixXd P = step.Phi * P0 * step.Phi.transpose() + step.Qd;
  EXPECT_LT(relativeError(P, reference.P), tolerance) << where;
  const double cost = P0.cwiseProduct(step.cost_gramian).sum() + step.noise_cost;
  EXPECT_LT(relativeError(cost, reference.cost), tolerance) << where;
}

struct Plant {
  std::string label;
  MatrixXd A;
};

std::vector<Plant> diagonalizablePlants() {
  Rng rng(20240601);
  std::vector<Plant> plants;
  const MatrixXd g4 = gaussianMatrix(4, 4, rng) / 2.0;
  plants.push_back({"general random A (complex pairs)", g4});
  plants.push_back({"stable random A", g4 - 1.5 * MatrixXd::Identity(4, 4)});
  plants.push_back({"unstable random A", g4 + 0.7 * MatrixXd::Identity(4, 4)});
  const MatrixXd g5 = gaussianMatrix(5, 5, rng);
  plants.push_back({"symmetric A (real eigenvalues)", (g5 + g5.transpose()) / 4.0});
  MatrixXd oscillator(3, 3);
  oscillator << -0.1, 2.0, 0.0, -2.0, -0.1, 0.0, 0.3, 0.0, 0.4;
  plants.push_back({"damped oscillator plus a real mode", oscillator});
  return plants;
}

TEST(LtiTransition, MatchesFineStepIntegrationOnDiagonalizablePlants) {
  Rng rng(7);
  for (const Plant& plant : diagonalizablePlants()) {
    const Eigen::Index n = plant.A.rows();
    const MatrixXd Q = randomSpd(n, rng);
    const MatrixXd W = randomSpd(n, rng);
    const LtiTransition transition(plant.A, Q, W);
    EXPECT_EQ(transition.method(), TransitionMethod::kModal) << plant.label;
    EXPECT_LT(transition.eigenvectorCondition(), LtiTransition::kMaxEigenvectorCondition);
    for (const double dt : {1e-3, 0.2, 1.0, 3.0}) {
      expectMatchesFineSteps(transition, plant.A, Q, W, dt, 1e-10, plant.label);
    }
  }
}

TEST(LtiTransition, HandlesDefectivePlantsExactly) {
  // Nilpotent plants take the polynomial path, other defective ones Van Loan; forcing Van Loan
  // on the nilpotent ones checks that path against the fine steps too.
  Rng rng(8);
  struct Case {
    std::string label;
    MatrixXd A;
    TransitionMethod expected;
  };
  MatrixXd constant_velocity = MatrixXd::Zero(4, 4);  // (x, y, vx, vy)
  constant_velocity(0, 2) = 1.0;
  constant_velocity(1, 3) = 1.0;
  const std::vector<Case> cases = {
      {"double integrator", (MatrixXd(2, 2) << 0, 1, 0, 0).finished(),
       TransitionMethod::kPolynomial},
      {"nilpotent 3 x 3", (MatrixXd(3, 3) << 0, 1, 0, 0, 0, 1, 0, 0, 0).finished(),
       TransitionMethod::kPolynomial},
      {"2-D constant velocity", constant_velocity, TransitionMethod::kPolynomial},
      {"Jordan block at -1", (MatrixXd(2, 2) << -1, 1, 0, -1).finished(),
       TransitionMethod::kVanLoan},
      {"unstable Jordan block plus stable mode",
       (MatrixXd(3, 3) << 0.5, 1, 0, 0, 0.5, 0, 0.2, 0, -1).finished(), TransitionMethod::kVanLoan},
      {"nearly defective (gap 1e-6)", (MatrixXd(2, 2) << -1, 1, 0, -1 - 1e-6).finished(),
       TransitionMethod::kVanLoan},
  };
  for (const Case& c : cases) {
    const Eigen::Index n = c.A.rows();
    const MatrixXd Q = randomSpd(n, rng);
    const MatrixXd W = randomSpd(n, rng);
    const LtiTransition automatic(c.A, Q, W);
    EXPECT_EQ(automatic.method(), c.expected) << c.label;
    const LtiTransition van_loan(c.A, Q, W, TransitionMethod::kVanLoan);
    for (const double dt : {1e-3, 0.2, 1.0, 3.0}) {
      expectMatchesFineSteps(automatic, c.A, Q, W, dt, 1e-10, c.label);
      if (c.expected != TransitionMethod::kVanLoan) {
        expectMatchesFineSteps(van_loan, c.A, Q, W, dt, 1e-10, c.label + " (Van Loan)");
      }
    }
  }
}

TEST(LtiTransition, AutomaticChoiceStaysAccurateAcrossNearlyDefectivePlants) {
  // A = [[-1, 1], [0, -1 - gap]]: cond(V) ~ 2/gap, so the choice switches to Van Loan near
  // gap = 2e-2; either side must stay accurate.
  const MatrixXd Q = (MatrixXd(2, 2) << 1.0, 0.3, 0.3, 2.0).finished();
  const MatrixXd W = MatrixXd::Identity(2, 2);
  for (int k = 0; k <= 10; ++k) {
    const double gap = std::pow(10.0, -k);
    const MatrixXd A = (MatrixXd(2, 2) << -1, 1, 0, -1 - gap).finished();
    const LtiTransition transition(A, Q, W);
    const bool well_conditioned =
        transition.eigenvectorCondition() <= LtiTransition::kMaxEigenvectorCondition;
    EXPECT_EQ(transition.method(),
              well_conditioned ? TransitionMethod::kModal : TransitionMethod::kVanLoan);
    expectMatchesFineSteps(transition, A, Q, W, 1.0, 1e-10, "gap 1e-" + std::to_string(k));
  }
}

TEST(LtiTransition, BrownianMotionMatchesClosedForm) {
  // A = 0: Phi = I, Qd = Q dt, G = W dt, noise_cost = <W, Q> dt² / 2.
  Rng rng(9);
  const MatrixXd Q = randomSpd(3, rng);
  const MatrixXd W = randomPsdRankOne(3, rng);
  for (const TransitionMethod method :
       {TransitionMethod::kPolynomial, TransitionMethod::kModal, TransitionMethod::kVanLoan}) {
    const LtiTransition transition(MatrixXd::Zero(3, 3), Q, W, method);
    EXPECT_EQ(transition.method(), method);
    if (method == TransitionMethod::kPolynomial) {
      EXPECT_EQ(LtiTransition(MatrixXd::Zero(3, 3), Q, W).method(), method);  // automatic
    }
    for (const double dt : {1e-9, 1e-3, 0.7, 5.0, 100.0}) {
      const IntervalTransition step = transition.over(dt);
      EXPECT_LT(relativeError(step.Phi, MatrixXd::Identity(3, 3)), 1e-15);
      EXPECT_LT(relativeError(step.Qd, Q * dt), 1e-14);
      EXPECT_LT(relativeError(step.cost_gramian, W * dt), 1e-14);
      EXPECT_LT(relativeError(step.noise_cost, W.cwiseProduct(Q).sum() * dt * dt / 2), 1e-14);
    }
  }
}

TEST(LtiTransition, DoubleIntegratorMatchesClosedForm) {
  // A = [[0, 1], [0, 0]], Q = diag(0, q), W = I:
  //   e^{As} = [[1, s], [0, 1]],  Qd = q [[dt³/3, dt²/2], [dt²/2, dt]],
  //   G = [[dt, dt²/2], [dt²/2, dt + dt³/3]],  noise_cost = ∫ tr Qd(s) ds = q (dt⁴/12 + dt²/2).
  const double q = 0.8;
  const MatrixXd A = (MatrixXd(2, 2) << 0, 1, 0, 0).finished();
  const MatrixXd Q = (MatrixXd(2, 2) << 0, 0, 0, q).finished();
  for (const TransitionMethod method : {TransitionMethod::kAutomatic, TransitionMethod::kVanLoan}) {
    const LtiTransition transition(A, Q, MatrixXd::Identity(2, 2), method);
    EXPECT_EQ(transition.method(), method == TransitionMethod::kAutomatic
                                       ? TransitionMethod::kPolynomial
                                       : TransitionMethod::kVanLoan);
    for (const double dt : {1e-4, 0.05, 1.0, 4.0, 20.0}) {
      const IntervalTransition step = transition.over(dt);
      const double dt2 = dt * dt;
      const double dt3 = dt2 * dt;
      EXPECT_LT(relativeError(step.Phi, (MatrixXd(2, 2) << 1, dt, 0, 1).finished()), 1e-14);
      EXPECT_LT(
          relativeError(step.Qd, q * (MatrixXd(2, 2) << dt3 / 3, dt2 / 2, dt2 / 2, dt).finished()),
          1e-13)
          << "dt = " << dt;
      EXPECT_LT(relativeError(step.cost_gramian,
                              (MatrixXd(2, 2) << dt, dt2 / 2, dt2 / 2, dt + dt3 / 3).finished()),
                1e-13)
          << "dt = " << dt;
      EXPECT_LT(relativeError(step.noise_cost, q * (dt2 * dt2 / 12 + dt2 / 2)), 1e-13)
          << "dt = " << dt;
    }
  }
}

// ψ1(μ, t) = ∫_0^t e^{μs} ds and ψ2(μ, t) = ∫_0^t ψ1(μ, s) ds in long double, for the closed
// forms below. ψ2 = t² Σ_k (μt)^k / (k+2)! by its Taylor series below |μt| = 0.01 (20 terms
// leave < 1e-40), where the closed form would cancel; both are good to ~1e-18 relative.
long double psi1(long double mu, long double t) { return std::expm1(mu * t) / mu; }
long double psi2(long double mu, long double t) {
  const long double z = mu * t;
  if (std::abs(z) >= 0.01L) return (std::expm1(z) - z) / (mu * mu);
  long double sum = 0.0L;
  long double term = 0.5L;  // z^k / (k+2)! at k = 0
  for (int k = 0; k < 20; ++k) {
    sum += term;
    term *= z / (k + 3);
  }
  return t * t * sum;
}
std::complex<long double> psi1(std::complex<long double> mu, long double t) {
  return (std::exp(mu * t) - 1.0L) / mu;
}
std::complex<long double> psi2(std::complex<long double> mu, long double t) {
  return (psi1(mu, t) - t) / mu;
}

TEST(LtiTransition, ScalarPlantMatchesClosedFormAcrossTheSeriesSwitch) {
  // ẋ = a x: Phi = e^{a dt}, Qd = q ψ1(2a), G = w ψ1(2a), noise_cost = w q ψ2(2a). The sweep of
  // |2a dt| from 1e-6 to 30 crosses the switch between series and closed form at 0.5.
  const double q = 1.7;
  const double w = 0.6;
  for (const double a : {-1.3, 0.4}) {
    const LtiTransition transition(MatrixXd::Constant(1, 1, a), MatrixXd::Constant(1, 1, q),
                                   MatrixXd::Constant(1, 1, w));
    for (double z = 1e-6; z < 30.0; z *= 1.37) {
      const double dt = z / (2.0 * std::abs(a));
      const IntervalTransition step = transition.over(dt);
      const long double mu = 2.0L * a;
      const std::string where = "a = " + std::to_string(a) + ", dt = " + std::to_string(dt);
      EXPECT_LT(relativeError(step.Phi(0, 0), std::exp(a * dt)), 1e-14) << where;
      EXPECT_LT(relativeError(step.Qd(0, 0), static_cast<double>(q * psi1(mu, dt))), 1e-14)
          << where;
      EXPECT_LT(relativeError(step.cost_gramian(0, 0), static_cast<double>(w * psi1(mu, dt))),
                1e-14)
          << where;
      EXPECT_LT(relativeError(step.noise_cost, static_cast<double>(w * q * psi2(mu, dt))), 1e-14)
          << where;
    }
  }
}

TEST(LtiTransition, RotatingPlantMatchesClosedFormAcrossTheSeriesSwitch) {
  // A = a I + b [[0, 1], [-1, 0]] has eigenvalues a ± ib and e^{As} = e^{as} R(bs) with
  // R(θ) = [[cos θ, sin θ], [-sin θ, cos θ]]. For Q = diag(q1, q2), W = diag(w1, w2), with
  // m = mean, d = half-difference and μ = 2a + 2ib:
  //   Qd = m_q ψ1(2a) I + d_q [[Re ψ1(μ), -Im ψ1(μ)], [-Im ψ1(μ), -Re ψ1(μ)]]
  //   G  = m_w ψ1(2a) I + d_w [[Re ψ1(μ),  Im ψ1(μ)], [ Im ψ1(μ), -Re ψ1(μ)]]
  //   noise_cost = (w1 + w2) m_q ψ2(2a) + (w1 - w2) d_q Re ψ2(μ).
  const double a = -0.3;
  const double b = 1.1;
  const double q1 = 2.0, q2 = 0.5, w1 = 1.5, w2 = 0.2;
  const MatrixXd A = (MatrixXd(2, 2) << a, b, -b, a).finished();
  const MatrixXd Q = Eigen::Vector2d(q1, q2).asDiagonal();
  const MatrixXd W = Eigen::Vector2d(w1, w2).asDiagonal();
  const LtiTransition transition(A, Q, W);
  EXPECT_EQ(transition.method(), TransitionMethod::kModal);
  const double mq = (q1 + q2) / 2, dq = (q1 - q2) / 2, mw = (w1 + w2) / 2, dw = (w1 - w2) / 2;
  const std::complex<long double> mu(2.0L * a, 2.0L * b);
  for (double z = 1e-2; z < 30.0; z *= 1.41) {
    const double dt = z / std::abs(std::complex<double>(2 * a, 2 * b));
    const IntervalTransition step = transition.over(dt);
    const double c = std::cos(b * dt), s = std::sin(b * dt);
    const MatrixXd Phi = std::exp(a * dt) * (MatrixXd(2, 2) << c, s, -s, c).finished();
    const double real = static_cast<double>(psi1(2.0L * a, dt));
    const double re = static_cast<double>(psi1(mu, dt).real());
    const double im = static_cast<double>(psi1(mu, dt).imag());
    const MatrixXd Qd = mq * real * MatrixXd::Identity(2, 2) +
                        dq * (MatrixXd(2, 2) << re, -im, -im, -re).finished();
    const MatrixXd G =
        mw * real * MatrixXd::Identity(2, 2) + dw * (MatrixXd(2, 2) << re, im, im, -re).finished();
    const double noise = static_cast<double>((w1 + w2) * mq * psi2(2.0L * a, dt) +
                                             (w1 - w2) * dq * psi2(mu, dt).real());
    const std::string where = "dt = " + std::to_string(dt);
    EXPECT_LT(relativeError(step.Phi, Phi), 1e-14) << where;
    EXPECT_LT(relativeError(step.Qd, Qd), 1e-13) << where;
    EXPECT_LT(relativeError(step.cost_gramian, G), 1e-13) << where;
    EXPECT_LT(relativeError(step.noise_cost, noise), 1e-12) << where;
  }
}

TEST(LtiTransition, ModalAndVanLoanAgreeWhenVanLoanIsForced) {
  Rng rng(10);
  for (const Plant& plant : diagonalizablePlants()) {
    const Eigen::Index n = plant.A.rows();
    const MatrixXd Q = randomSpd(n, rng);
    const MatrixXd W = randomPsdRankOne(n, rng);
    const LtiTransition modal(plant.A, Q, W, TransitionMethod::kModal);
    const LtiTransition van_loan(plant.A, Q, W, TransitionMethod::kVanLoan);
    EXPECT_EQ(modal.method(), TransitionMethod::kModal);
    EXPECT_EQ(van_loan.method(), TransitionMethod::kVanLoan);
    for (const double dt : {1e-5, 0.1, 0.9, 2.5}) {
      const IntervalTransition x = modal.over(dt);
      const IntervalTransition y = van_loan.over(dt);
      const std::string where = plant.label + ", dt = " + std::to_string(dt);
      EXPECT_LT(relativeError(x.Phi, y.Phi), 1e-12) << where;
      EXPECT_LT(relativeError(x.Qd, y.Qd), 1e-12) << where;
      EXPECT_LT(relativeError(x.cost_gramian, y.cost_gramian), 1e-12) << where;
      EXPECT_LT(relativeError(x.noise_cost, y.noise_cost), 1e-12) << where;
    }
  }
}

TEST(LtiTransition, OutputsAreExactlySymmetricAndReuseTheirStorage) {
  Rng rng(11);
  const MatrixXd A = gaussianMatrix(4, 4, rng);
  const LtiTransition transition(A, randomSpd(4, rng), randomSpd(4, rng));
  IntervalTransition step;
  transition.over(0.3, step);
  const double* storage = step.Qd.data();
  transition.over(0.6, step);
  EXPECT_EQ(step.Qd.data(), storage);
  EXPECT_EQ(step.Qd, step.Qd.transpose());
  EXPECT_EQ(step.cost_gramian, step.cost_gramian.transpose());
  const IntervalTransition fresh = transition.over(0.6);
  EXPECT_EQ(fresh.Qd, step.Qd);
  EXPECT_EQ(fresh.noise_cost, step.noise_cost);
}

TEST(LtiTransition, ZeroIntervalIsTheIdentity) {
  Rng rng(12);
  const LtiTransition transition(gaussianMatrix(3, 3, rng), randomSpd(3, rng), randomSpd(3, rng));
  const IntervalTransition step = transition.over(0.0);
  EXPECT_EQ(step.Phi, MatrixXd::Identity(3, 3));
  EXPECT_EQ(step.Qd, MatrixXd::Zero(3, 3));
  EXPECT_EQ(step.cost_gramian, MatrixXd::Zero(3, 3));
  EXPECT_EQ(step.noise_cost, 0.0);
}

TEST(LtiTransition, RejectsBadIntervalsShapesAndForcedMethodsThatDoNotApply) {
  const MatrixXd I2 = MatrixXd::Identity(2, 2);
  const LtiTransition transition(-I2, I2, I2);
  EXPECT_THROW((void)transition.over(-1e-3), InputError);
  EXPECT_THROW((void)transition.over(std::numeric_limits<double>::quiet_NaN()), InputError);
  EXPECT_THROW((void)transition.over(std::numeric_limits<double>::infinity()), InputError);
  EXPECT_THROW(LtiTransition(MatrixXd::Zero(2, 3), I2, I2), InputError);
  EXPECT_THROW(LtiTransition(-I2, MatrixXd::Identity(3, 3), I2), InputError);
  EXPECT_THROW(LtiTransition(-I2, I2, MatrixXd::Identity(3, 3)), InputError);
  const MatrixXd double_integrator = (MatrixXd(2, 2) << 0, 1, 0, 0).finished();
  EXPECT_THROW(LtiTransition(double_integrator, I2, I2, TransitionMethod::kModal), InputError);
  EXPECT_THROW(LtiTransition(-I2, I2, I2, TransitionMethod::kPolynomial), InputError);
  EXPECT_GT(LtiTransition(double_integrator, I2, I2).eigenvectorCondition(),
            LtiTransition::kDefectiveEigenvectorCondition);
}

// The cache gives over()'s numbers bit for bit, whether a length is new, repeated or evicted by
// another that maps to its slot; what it counts as hits are exactly the repeats still held.
TEST(TransitionCache, GivesExactlyTheStepOfEveryLengthWhetherCachedOrNot) {
  Rng rng(31);
  // A is not symmetric.
  const LtiTransition transition(gaussianMatrix(4, 4, rng), randomSpd(4, rng), randomSpd(4, rng));
  for (const std::size_t slots : {1, 4, 256}) {
    TransitionCache cache(transition, slots);
    EXPECT_EQ(cache.slots(), slots);
    // Lengths of whole ticks (3 s / 2^20), as the fusion center sees, and a few that are not.
    const double tick = 3.0 / 1048576.0;
    std::vector<double> lengths;
    for (int i = 0; i < 400; ++i) {
      const int ticks = 1 + static_cast<int>(rng.uniform() * 12.0);
      lengths.push_back(i % 7 == 0 ? rng.uniform() : tick * ticks);
    }
    std::vector<double> held(cache.slots(), -1.0);  // what a cache of that size must hold
    std::uint64_t repeats = 0;
    for (const double dt : lengths) {
      const IntervalTransition expected = transition.over(dt);
      const IntervalTransition& got = cache.over(dt);
      EXPECT_EQ(got.Phi, expected.Phi) << dt;
      EXPECT_EQ(got.Qd, expected.Qd) << dt;
      EXPECT_EQ(got.cost_gramian, expected.cost_gramian) << dt;
      EXPECT_EQ(got.noise_cost, expected.noise_cost) << dt;
      if (std::find(held.begin(), held.end(), dt) != held.end()) ++repeats;
      if (slots == 1) held[0] = dt;
    }
    EXPECT_EQ(cache.hits() + cache.misses(), lengths.size());
    if (slots == 1) {
      EXPECT_EQ(cache.hits(), repeats);
    }
    if (slots == 256) {
      EXPECT_GT(cache.hits(), lengths.size() / 2);  // 12 tick lengths repeat
    }
  }
}

TEST(TransitionCache, ABadLengthThrowsAndLeavesTheCacheWhole) {
  Rng rng(32);
  const LtiTransition transition(gaussianMatrix(3, 3, rng), randomSpd(3, rng), randomSpd(3, rng));
  TransitionCache cache(transition, 8);
  const IntervalTransition expected = transition.over(0.25);
  (void)cache.over(0.25);
  EXPECT_THROW((void)cache.over(-1.0), InputError);
  EXPECT_THROW((void)cache.over(std::numeric_limits<double>::quiet_NaN()), InputError);
  EXPECT_EQ(cache.over(0.25).Phi, expected.Phi);
  EXPECT_EQ(cache.hits(), 1u);
}

}  // namespace
}  // namespace sensornet
