// The tests' Eigen near-assertion (tests/support/eigen_near.hpp): it passes within its bound,
// absolute for entries at most 1 in size and relative above, and fails (naming the worst entry)
// on a wrong entry, a wrong shape or a NaN.

#include "support/eigen_near.hpp"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <limits>

namespace sensornet {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using testing::relativeError;

TEST(EigenNear, PassesWithinAnAbsoluteBoundNearZeroAndARelativeOneElsewhere) {
  const MatrixXd expected = (MatrixXd(2, 2) << 0.0, 0.5, 1000.0, -2e6).finished();
  MatrixXd actual = expected;
  EXPECT_MATRIX_NEAR(actual, expected, 0.0);
  actual(0, 0) += 0.9e-9;  // absolute: |b| = 0
  actual(0, 1) -= 0.9e-9;  // absolute: |b| < 1
  actual(1, 0) += 0.9e-6;  // relative: 1e-9 * 1000
  actual(1, 1) -= 1.9e-3;  // relative: 1e-9 * 2e6
  EXPECT_MATRIX_NEAR(actual, expected, 1e-9);
  ASSERT_MATRIX_NEAR(actual.col(1), expected.col(1), 1e-9);  // expressions and vectors too
}

TEST(EigenNear, FailsOnAWrongEntryAndNamesTheWorst) {
  const MatrixXd expected = (MatrixXd(2, 3) << 1, 2, 3, 4, 5, 6).finished();
  MatrixXd actual = expected;
  actual(0, 2) += 1e-8;  // 3.3e-9 of its size: off
  actual(1, 1) += 1e-6;  // 2e-7 of its size: the worst
  EXPECT_NONFATAL_FAILURE(EXPECT_MATRIX_NEAR(actual, expected, 1e-9),
                          "in 2 of 6 entries; the worst is (1, 1): actual 5.0000010000000001, "
                          "expected 5");
  // Near zero the bound is absolute: 1e-9 off an expected 0 is too far at 1e-10.
  const VectorXd zero = VectorXd::Zero(3);
  const VectorXd almost = (VectorXd(3) << 0.0, 1e-9, 0.0).finished();
  EXPECT_NONFATAL_FAILURE(EXPECT_MATRIX_NEAR(almost, zero, 1e-10), "the worst is (1, 0)");
  EXPECT_NONFATAL_FAILURE(EXPECT_MATRIX_NEAR(almost, zero, 0.0), "in 1 of 3 entries");
}

TEST(EigenNear, FailsOnADifferentShapeOrANaN) {
  EXPECT_NONFATAL_FAILURE(EXPECT_MATRIX_NEAR(MatrixXd::Zero(2, 3), MatrixXd::Zero(3, 2), 1.0),
                          "is 2x3 but MatrixXd::Zero(3, 2) is 3x2");
  MatrixXd nan = MatrixXd::Identity(2, 2);
  nan(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NONFATAL_FAILURE(EXPECT_MATRIX_NEAR(nan, MatrixXd::Identity(2, 2), 1.0),
                          "the worst is (1, 0)");
  EXPECT_NONFATAL_FAILURE(EXPECT_MATRIX_NEAR(MatrixXd::Identity(2, 2), nan, 1.0),
                          "the worst is (1, 0)");
  EXPECT_NONFATAL_FAILURE(
      EXPECT_MATRIX_NEAR(MatrixXd::Identity(2, 2), MatrixXd::Identity(2, 2), -1.0), "not >= 0");
}

TEST(EigenNear, RelativeErrorIsTheFrobeniusNormOfTheDifferenceOverTheExpecteds) {
  const MatrixXd expected = (MatrixXd(2, 2) << 3, 0, 0, 4).finished();  // norm 5
  const MatrixXd actual = (MatrixXd(2, 2) << 3, 0.5, 0, 4).finished();
  EXPECT_DOUBLE_EQ(relativeError(actual, expected), 0.1);
  EXPECT_DOUBLE_EQ(relativeError(-3.0, -2.0), 0.5);
  EXPECT_EQ(relativeError(MatrixXd::Zero(2, 2), MatrixXd::Zero(2, 2)), 0.0);
}

}  // namespace
}  // namespace sensornet
