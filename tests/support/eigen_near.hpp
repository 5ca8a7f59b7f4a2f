#pragma once
// Comparing Eigen matrices and vectors in tests.
//
//   EXPECT_MATRIX_NEAR(filter.mean(), expected.mean, 1e-12);
//   ASSERT_MATRIX_NEAR(p, p.transpose(), 0.0);  // exactly symmetric
//
// passes when the shapes agree and every entry has |a - b| <= tolerance * max(1, |b|), b the
// expected entry: an absolute tolerance where the expected entry is at most 1 in size, a relative
// one elsewhere (tolerance 0: equal entry by entry). A failure names the worst entry (row,
// column, both values, the difference and what was allowed), how many entries are off, and
// prints both matrices. The same check is `EXPECT_PRED_FORMAT3(sensornet::testing::matrixNear,
// actual, expected, tolerance)`.
//
// relativeError(actual, expected) is the number ‖a - b‖_F / ‖b‖_F (|a - b| / |b| for scalars),
// for a test whose bound is on the relative error of the whole matrix:
//
//   EXPECT_LT(relativeError(step.Qd, reference.Qd), 1e-13);

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace sensornet::testing {

// ‖actual - expected‖_F / ‖expected‖_F; 0 when both are zero.
[[nodiscard]] inline double relativeError(const Eigen::MatrixXd& actual,
                                          const Eigen::MatrixXd& expected) {
  return (actual - expected).norm() / std::max(expected.norm(), 1e-300);
}
[[nodiscard]] inline double relativeError(double actual, double expected) {
  return std::abs(actual - expected) / std::max(std::abs(expected), 1e-300);
}

template <typename Actual, typename Expected>
[[nodiscard]] ::testing::AssertionResult matrixNear(const char* actual_text,
                                                    const char* expected_text,
                                                    const char* tolerance_text,
                                                    const Eigen::MatrixBase<Actual>& actual_in,
                                                    const Eigen::MatrixBase<Expected>& expected_in,
                                                    double tolerance) {
  const Eigen::MatrixXd actual = actual_in.template cast<double>();
  const Eigen::MatrixXd expected = expected_in.template cast<double>();
  const auto shape = [](const Eigen::MatrixXd& m) {
    return std::to_string(m.rows()) + "x" + std::to_string(m.cols());
  };
  if (!(tolerance >= 0.0)) {
    return ::testing::AssertionFailure()
           << "the tolerance " << tolerance_text << " is " << tolerance << ", not >= 0";
  }
  if (actual.rows() != expected.rows() || actual.cols() != expected.cols()) {
    return ::testing::AssertionFailure() << actual_text << " is " << shape(actual) << " but "
                                         << expected_text << " is " << shape(expected);
  }
  // The worst entry: the largest difference in units of its own allowance max(1, |b|); a NaN
  // difference is worse than any number.
  Eigen::Index worst_row = -1, worst_col = -1, off = 0;
  double worst = -1.0;
  for (Eigen::Index c = 0; c < actual.cols(); ++c) {
    for (Eigen::Index r = 0; r < actual.rows(); ++r) {
      const double a = actual(r, c), b = expected(r, c);
      if (a == b) continue;  // also equal infinities
      const double scale = std::max(1.0, std::abs(b));
      const double difference = std::abs(a - b);
      if (difference <= tolerance * scale) continue;
      ++off;
      const double scaled =
          std::isnan(difference) ? std::numeric_limits<double>::infinity() : difference / scale;
      if (scaled > worst) {
        worst = scaled;
        worst_row = r;
        worst_col = c;
      }
    }
  }
  if (off == 0) return ::testing::AssertionSuccess();

  const double a = actual(worst_row, worst_col), b = expected(worst_row, worst_col);
  std::ostringstream out;
  out.precision(17);
  const Eigen::IOFormat full(Eigen::FullPrecision, 0, ", ", "\n", "  [", "]");
  out << actual_text << " differs from " << expected_text << " by more than " << tolerance_text
      << " = " << tolerance << " (times max(1, |expected|)) in " << off << " of " << actual.size()
      << " entries; the worst is (" << worst_row << ", " << worst_col << "): actual " << a
      << ", expected " << b << ", |difference| " << std::abs(a - b) << " > allowed "
      << tolerance * std::max(1.0, std::abs(b));
  if (actual.size() <= 400) {
    out << "\n"
        << actual_text << " =\n"
        << actual.format(full) << "\n"
        << expected_text << " =\n"
        << expected.format(full);
  }
  return ::testing::AssertionFailure() << out.str();
}

}  // namespace sensornet::testing

#define EXPECT_MATRIX_NEAR(actual, expected, tolerance) \
  EXPECT_PRED_FORMAT3(::sensornet::testing::matrixNear, actual, expected, tolerance)
#define ASSERT_MATRIX_NEAR(actual, expected, tolerance) \
  ASSERT_PRED_FORMAT3(::sensornet::testing::matrixNear, actual, expected, tolerance)
