// The information-form transcription at scale (issue 14): U built from the sensors with a
// nonzero rate only, the reverse pass without rates, and the rate gradient <G_k, S_j> of every
// interval computed after the reverse pass, split over threads. Checked against independent
// computations: central differences of the cost, and the closed form of a drift-free plant.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "sensornet/core/random.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/planning/surrogate_transcription.hpp"
#include "support/eigen_near.hpp"

namespace sensornet {
namespace {

using Eigen::MatrixXd;

Scenario paperScenario(int n, int m, int intervals, std::uint64_t seed) {
  RandomPlantSpec spec;
  spec.state_dim = n;
  spec.sensor_count = m;
  spec.intervals = intervals;
  spec.seed = seed;
  return generateRandomScenario(spec);
}

// Rates in [0.1, 1], with about a third of them exactly zero (as in plans at large M).
MatrixXd sparseRates(const Scenario& s, std::uint64_t seed) {
  Rng rng = Rng::keyed(seed, 17);
  MatrixXd rates(s.intervals, s.sensorCount());
  for (int k = 0; k < rates.rows(); ++k) {
    for (int j = 0; j < rates.cols(); ++j) {
      const double u = rng.uniform();
      rates(k, j) = u < 1.0 / 3.0 ? 0.0 : 0.1 + 0.9 * rng.uniform();
    }
  }
  return rates;
}

// Central differences, step 1e-5: truncation about 1e-10 and rounding about 1e-11 relative
// here, far below the 1e-6 tolerance. A step across a zero rate is fine: the discretized cost
// is a polynomial-rational function of the rates, smooth through zero.
TEST(InformationTranscriptionAtScale, GradientWithZeroRatesOnTwoThreadsMatchesCentralDifferences) {
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    Scenario s = paperScenario(4, 7, 6, seed);
    s.sensors[2].H = s.sensors[2].H.replicate(2, 1).eval();  // a two-row sensor too
    s.sensors[2].H.row(1) *= 0.5;
    s.sensors[2].R = (MatrixXd(2, 2) << 2.0, 0.3, 0.3, 1.0).finished();
    s.cost.W = 0.5 * MatrixXd::Identity(4, 4);  // the running cost as well
    TranscriptionOptions options;
    options.threads = 2;
    SurrogateTranscription t(SurrogateForm::Information, s, options);
    const MatrixXd rates = sparseRates(s, seed);
    ASSERT_GT((rates.array() == 0.0).count(), 5);
    const CostGradient cg = t.costAndGradient(rates);
    ASSERT_TRUE(std::isfinite(cg.cost)) << "seed " << seed;
    MatrixXd fd(rates.rows(), rates.cols());
    for (int k = 0; k < rates.rows(); ++k) {
      for (int j = 0; j < rates.cols(); ++j) {
        const double step = 1e-5;
        MatrixXd plus = rates, minus = rates;
        plus(k, j) += step;
        minus(k, j) -= step;
        fd(k, j) = (t.cost(plus) - t.cost(minus)) / (2.0 * step);
      }
    }
    const double scale = fd.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    // In units of the largest finite difference: every entry within 1e-6 of it.
    EXPECT_MATRIX_NEAR(cg.gradient / scale, fd / scale, 1e-6)
        << "adjoint against finite differences";
  }
}

// With A = 0, Q = 0 and W = 0 the flow is Y' = U_k on interval k, which RK4 integrates exactly:
// Y(T) = Y0 + h Σ_k U_k, J = <W_T, Y(T)^{-1}> and ∂J/∂λ_kj = -h <Y(T)^{-1} W_T Y(T)^{-1}, S_j>,
// computed here from Scenario::informationIncrements, on an instance large enough that the
// gradient products run on two threads (N M n² = 30 x 300 x 400 > 1e6) and in blocks of rows
// (300 = 128 + 128 + 44).
TEST(InformationTranscriptionAtScale, GradientMatchesTheClosedFormOfADriftFreePlant) {
  Scenario s = paperScenario(20, 300, 30, 3);
  s.plant.A.setZero();
  s.plant.Q.setZero();
  s.cost.WT = MatrixXd::Identity(20, 20) + 0.1 * MatrixXd::Ones(20, 20);
  const MatrixXd rates = sparseRates(s, 3);
  const auto increments = s.informationIncrements();
  const double h = s.intervalLength();
  MatrixXd Y = s.plant.P0.inverse();
  for (int k = 0; k < s.intervals; ++k) {
    for (int j = 0; j < s.sensorCount(); ++j) {
      Y += h * rates(k, j) * increments[static_cast<std::size_t>(j)];
    }
  }
  const MatrixXd P = Y.llt().solve(MatrixXd::Identity(20, 20));
  const double cost = (s.cost.WT * P).trace();
  const MatrixXd PWP = P * s.cost.WT * P;
  MatrixXd gradient(s.intervals, s.sensorCount());
  for (int j = 0; j < s.sensorCount(); ++j) {
    const double pairing = PWP.cwiseProduct(increments[static_cast<std::size_t>(j)]).sum();
    gradient.col(j).setConstant(-h * pairing);
  }
  for (const int threads : {1, 2}) {
    TranscriptionOptions options;
    options.threads = threads;
    SurrogateTranscription t(SurrogateForm::Information, s, options);
    const CostGradient cg = t.costAndGradient(rates);
    EXPECT_NEAR(cg.cost, cost, 1e-10 * cost);
    const double scale = gradient.cwiseAbs().maxCoeff();
    // In units of the largest entry: every entry within 1e-9 of it.
    EXPECT_MATRIX_NEAR(cg.gradient / scale, gradient / scale, 1e-9) << threads;
  }
}

// Every interval's products are computed by the same code whichever thread runs them, so the
// gradient is the same to the last bit for any thread count (and the cost never depends on it).
TEST(InformationTranscriptionAtScale, GradientIsBitIdenticalForAnyThreadCount) {
  const Scenario s = paperScenario(12, 200, 30, 4);
  const MatrixXd rates = sparseRates(s, 4);
  CostGradient results[3];
  for (int threads = 1; threads <= 3; ++threads) {
    TranscriptionOptions options;
    options.threads = threads;
    SurrogateTranscription t(SurrogateForm::Information, s, options);
    results[threads - 1] = t.costAndGradient(rates);
  }
  for (int i = 1; i < 3; ++i) {
    EXPECT_EQ(results[i].cost, results[0].cost);
    EXPECT_TRUE(results[i].gradient == results[0].gradient) << "threads " << i + 1;
  }
}

TEST(InformationTranscriptionAtScale, RefusesANegativeThreadCount) {
  TranscriptionOptions options;
  options.threads = -1;
  EXPECT_ANY_THROW(
      SurrogateTranscription(SurrogateForm::Information, paperScenario(2, 3, 4, 5), options));
}

}  // namespace
}  // namespace sensornet
