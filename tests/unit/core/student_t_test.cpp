// Student's t quantiles against independent closed forms (df = 1, 2, 4), published table values
// and the normal limit.

#include "sensornet/core/student_t.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace sensornet {
namespace {

// Closed forms of the quantile (Hill 1970; Shaw 2006, "Sampling Student's T distribution").
double quantileDf1(double p) { return std::tan(std::numbers::pi * (p - 0.5)); }
double quantileDf2(double p) { return (2.0 * p - 1.0) / std::sqrt(2.0 * p * (1.0 - p)); }
double quantileDf4(double p) {
  const double alpha = 4.0 * p * (1.0 - p);
  const double q = std::cos(std::acos(std::sqrt(alpha)) / 3.0) / std::sqrt(alpha);
  return (p < 0.5 ? -1.0 : 1.0) * 2.0 * std::sqrt(q - 1.0);
}

TEST(StudentT, QuantilesMatchTheClosedFormsForOneTwoAndFourDegrees) {
  for (const double p : {0.001, 0.025, 0.1, 0.3, 0.5, 0.7, 0.9, 0.975, 0.995, 0.9999}) {
    const double q1 = quantileDf1(p), q2 = quantileDf2(p), q4 = quantileDf4(p);
    EXPECT_NEAR(studentTQuantile(p, 1.0), q1, 1e-9 * std::max(1.0, std::abs(q1))) << p;
    EXPECT_NEAR(studentTQuantile(p, 2.0), q2, 1e-9 * std::max(1.0, std::abs(q2))) << p;
    EXPECT_NEAR(studentTQuantile(p, 4.0), q4, 1e-9 * std::max(1.0, std::abs(q4))) << p;
  }
}

TEST(StudentT, TwoSidedNinetyFivePercentPointsMatchTheTable) {
  // Upper 2.5% points, to the 3 decimals printed in standard tables (e.g. Fisher & Yates).
  const std::pair<double, double> table[] = {{1, 12.706}, {3, 3.182}, {9, 2.262},
                                             {19, 2.093}, {29, 2.045}, {120, 1.980}};
  for (const auto& [df, value] : table) {
    EXPECT_NEAR(studentTQuantile(0.975, df), value, 5e-4) << "df " << df;
  }
}

TEST(StudentT, ApproachesTheNormalQuantileForManyDegrees) {
  EXPECT_NEAR(studentTQuantile(0.975, 1e7), 1.959963984540054, 1e-6);
}

TEST(StudentT, CdfInvertsTheQuantile) {
  for (const double df : {1.5, 7.0, 33.0}) {
    for (const double p : {0.01, 0.4, 0.975}) {
      EXPECT_NEAR(studentTCdf(studentTQuantile(p, df), df), p, 1e-12);
    }
  }
}

TEST(StudentT, RefusesProbabilitiesOutsideTheOpenUnitInterval) {
  EXPECT_THROW((void)studentTQuantile(0.0, 3.0), std::invalid_argument);
  EXPECT_THROW((void)studentTQuantile(1.0, 3.0), std::invalid_argument);
  EXPECT_THROW((void)studentTQuantile(0.5, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace sensornet

namespace sensornet {
namespace {

// Against values worked by hand with the tabled quantiles t_{0.975,4} = 2.7764451 and
// t_{0.975,1} = 12.7062047.
TEST(SampleMean, IsTheMeanTheSampleDeviationAndTheTInterval) {
  const std::vector<double> x{1.0, 2.0, 3.0, 4.0, 5.0};
  const SampleMean s = sampleMean(x);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_NEAR(s.std_dev, std::sqrt(2.5), 1e-15);
  EXPECT_NEAR(s.ci95, 2.7764451 * std::sqrt(2.5) / std::sqrt(5.0), 1e-6);
  const std::vector<double> one{7.0};
  EXPECT_EQ(sampleMean(one).mean, 7.0);
  EXPECT_TRUE(std::isinf(sampleMean(one).ci95));
  EXPECT_EQ(sampleMean(std::vector<double>{}).mean, 0.0);
}

TEST(SampleMean, PairedDifferenceIsThatOfTheDifferences) {
  const std::vector<double> a{1.0, 4.0};
  const std::vector<double> b{0.0, 1.0};  // differences 1 and 3
  const SampleMean d = pairedDifference(a, b);
  EXPECT_DOUBLE_EQ(d.mean, 2.0);
  EXPECT_NEAR(d.std_dev, std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(d.ci95, 12.7062047, 1e-6);
  EXPECT_THROW((void)pairedDifference(a, std::vector<double>{1.0}), std::invalid_argument);
}

}  // namespace
}  // namespace sensornet
