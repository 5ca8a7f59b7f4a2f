// The chi-square CDF and quantiles against closed forms: for even k, P(X <= x) =
// 1 - e^{-x/2} sum_{i < k/2} (x/2)^i / i!; for k = 1, erf(sqrt(x/2)); for k = 2 the quantile
// -2 ln(1 - p). And the NEES band against a Monte Carlo of the sum of squared normals.

#include "sensornet/core/chi_square.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace sensornet {
namespace {

double evenCdf(double x, int k) {
  double term = 1.0;
  double sum = 0.0;
  for (int i = 0; i < k / 2; ++i) {
    if (i > 0) term *= 0.5 * x / i;
    sum += term;
  }
  return 1.0 - std::exp(-0.5 * x) * sum;
}

TEST(ChiSquare, TheCdfIsTheClosedFormForEvenDegreesAndForOne) {
  for (const int k : {2, 4, 10, 40, 200}) {
    for (const double x : {0.01, 0.5, 1.0, 3.0, 9.5, 37.0, 80.0, 230.0}) {
      EXPECT_NEAR(chiSquareCdf(x, k), evenCdf(x, k), 1e-12) << "k " << k << " x " << x;
    }
  }
  for (const double x : {1e-6, 0.2, 1.0, 4.0, 12.0}) {
    EXPECT_NEAR(chiSquareCdf(x, 1), std::erf(std::sqrt(0.5 * x)), 1e-13) << x;
  }
  EXPECT_EQ(chiSquareCdf(0.0, 3), 0.0);
}

TEST(ChiSquare, TheQuantileInvertsTheCdf) {
  for (const double p : {1e-4, 0.0005, 0.05, 0.5, 0.9995}) {
    EXPECT_NEAR(chiSquareQuantile(p, 2), -2.0 * std::log1p(-p), 1e-10 * (1.0 - std::log1p(-p)));
    for (const double k : {1.0, 3.0, 8.0, 120.0, 4000.0}) {
      const double x = chiSquareQuantile(p, k);
      EXPECT_NEAR(chiSquareCdf(x, k), p, 1e-10) << "k " << k << " p " << p;
    }
  }
  EXPECT_THROW((void)chiSquareQuantile(1.0, 2), std::invalid_argument);
  EXPECT_THROW((void)chiSquareQuantile(0.5, 0), std::invalid_argument);
}

// The band holds the mean of K chi-square(n) draws with its stated probability: 20,000 trials
// (seed 5) of n = 3, K = 4 at 90% (a band narrow enough for the count to mean something); the
// count outside is Binomial(20000, 0.1): mean 2000, sd 42.4; accepted within 5 sd (a false alarm
// about 6e-7).
TEST(ChiSquare, TheNeesBandHoldsTheMeanOfIndependentEpisodesWithItsConfidence) {
  const NeesBand band = neesBand(3, 4, 0.90);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  int outside = 0;
  for (int trial = 0; trial < 20'000; ++trial) {
    double sum = 0.0;
    for (int i = 0; i < 12; ++i) {
      const double v = normal(rng);
      sum += v * v;
    }
    if (!band.holds(sum / 4.0)) ++outside;
  }
  EXPECT_NEAR(outside, 2000, 5 * 42.4);
  EXPECT_LT(band.low, 3.0);
  EXPECT_GT(band.high, 3.0);
  EXPECT_THROW((void)neesBand(0, 4, 0.9), std::invalid_argument);
}

}  // namespace
}  // namespace sensornet
